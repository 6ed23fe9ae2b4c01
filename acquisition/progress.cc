#include "acquisition/progress.h"

#include <utility>

namespace gf {
namespace {

class SilentProgress : public Progress {
 public:
  void Update(int, const std::string&) override {}
  void Finish() override {}
  void SetTotal(std::optional<int>) override {}
};

ProgressDisplay& Display() {
  static ProgressDisplay display;
  return display;
}

}  // namespace

void SetProgressDisplay(ProgressDisplay display) { Display() = std::move(display); }

std::unique_ptr<Progress> ShowProgress(const std::string& label, std::optional<int> total) {
  if (Display()) return Display()(label, total);
  return std::make_unique<SilentProgress>();
}

}  // namespace gf
