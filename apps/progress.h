// Terminal progress for long work: frames done, rate and time left, redrawn in place on stderr when
// it is a terminal (one final line otherwise, so logs stay readable).
#pragma once

#include <chrono>
#include <optional>
#include <string>

namespace gf {

class TerminalProgress {
 public:
  // label: what is being counted ("info", "reconstruct"); total: frames expected, if known.
  TerminalProgress(std::string label, std::optional<int> total);
  ~TerminalProgress();
  void Update(int done);
  void Finish();

 private:
  std::string label_;
  std::optional<int> total_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int done_ = 0;
  bool interactive_;
  bool finished_ = false;
};

}  // namespace gf
