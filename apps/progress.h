// Terminal progress for long work, the command line's display of the libraries' progress
// (acquisition/progress.h): frames done, rate and time left, redrawn in place on stderr (the line
// cleared each time), and a last line with the whole run's rate. Quiet when stderr is not a
// terminal (logs and scripts read the command's own output instead).
#pragma once

#include <chrono>
#include <optional>
#include <string>

#include "acquisition/progress.h"

namespace gf {

class TerminalProgress : public Progress {
 public:
  // label: what is being counted ("info", "reconstruct"); total: frames expected, if known.
  TerminalProgress(std::string label, std::optional<int> total);
  ~TerminalProgress() override;
  void Update(int done, const std::string& detail = "") override;
  void Finish() override;
  void SetTotal(std::optional<int> total) override { total_ = total; }

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

// Makes every library's progress (ShowProgress) a TerminalProgress; called once by main.
void ShowProgressOnTerminal();

}  // namespace gf
