// Terminal progress for long work: frames done, rate and time left, redrawn in place on stderr (the
// line cleared each time), and a last line with the whole run's rate. Quiet when stderr is not a
// terminal (logs and scripts read the command's own output instead).
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
  // `detail` follows the counts (e.g. what is still finishing after the last frame).
  void Update(int done, const std::string& detail = "");
  void Finish();
  // The frames expected, once known better (a frame range of the input).
  void SetTotal(std::optional<int> total) { total_ = total; }

 private:
  std::string label_;
  std::optional<int> total_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  int done_ = 0;
  bool drawn_ = false;
  bool interactive_;
  bool finished_ = false;
};

}  // namespace gf
