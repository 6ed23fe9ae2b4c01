#include "apps/progress.h"

#include <unistd.h>

#include <cstdio>

namespace gf {

TerminalProgress::TerminalProgress(std::string label, std::optional<int> total)
    : label_(std::move(label)),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_),
      interactive_(::isatty(STDERR_FILENO)) {}

// Ended without Finish() (an error is on its way): only close the in-place line.
TerminalProgress::~TerminalProgress() {
  if (!finished_ && interactive_ && done_ > 0) std::fputc('\n', stderr);
}

void TerminalProgress::Update(int done) {
  done_ = done;
  if (!interactive_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(200)) return;
  last_draw_ = now;
  const double seconds = std::chrono::duration<double>(now - start_).count();
  const double rate = seconds > 0 ? done / seconds : 0;
  if (total_ && *total_ > 0) {
    const double left = rate > 0 ? (*total_ - done) / rate : 0;
    std::fprintf(stderr, "\r%s: %d/%d frames  %.1f fps  %.0f s left   ", label_.c_str(), done,
                 *total_, rate, left);
  } else {
    std::fprintf(stderr, "\r%s: %d frames  %.1f fps   ", label_.c_str(), done, rate);
  }
  std::fflush(stderr);
}

void TerminalProgress::Finish() {
  if (finished_) return;
  finished_ = true;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s: %d frames in %.1f s (%.1f fps)\n", interactive_ ? "\r" : "",
               label_.c_str(), done_, seconds, seconds > 0 ? done_ / seconds : 0.0);
}

}  // namespace gf
