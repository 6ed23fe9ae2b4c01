// Progress of long work as a library reports it: frames (or items) done of a total, with a detail
// line. The libraries ask for a display with ShowProgress; what it shows is the program's choice:
// the command line installs a terminal line (apps/progress.h: frames done, rate, time left), and
// without one, as in tests and in programs that link the libraries, nothing is shown.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace gf {

class Progress {
 public:
  virtual ~Progress() = default;
  // `detail` follows the counts (e.g. what is still finishing after the last frame).
  virtual void Update(int done, const std::string& detail = "") = 0;
  // The whole work done (a display may print its last line); later calls do nothing.
  virtual void Finish() = 0;
  // The items expected, once known better (a frame range of the input).
  virtual void SetTotal(std::optional<int> total) = 0;
};

// Makes the display of one piece of work: `label` names it ("reconstruct", "bench: loading"),
// `total` is the items expected, if known.
using ProgressDisplay =
    std::function<std::unique_ptr<Progress>(const std::string& label, std::optional<int> total)>;

// Process-wide: set once by the program before its work starts (not while work runs); empty:
// nothing is shown.
void SetProgressDisplay(ProgressDisplay display);

// The display of one piece of work (never null: a silent one when no display is set).
std::unique_ptr<Progress> ShowProgress(const std::string& label, std::optional<int> total);

}  // namespace gf
