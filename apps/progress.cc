#include "apps/progress.h"

#include <unistd.h>

#include <cstdio>
#include <memory>

namespace gf {

TerminalProgress::TerminalProgress(std::string label, std::optional<int> total)
    : label_(std::move(label)),
      total_(total),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_),
      interactive_(::isatty(STDERR_FILENO)) {}

// Ended without Finish() (an error is on its way): only close the in-place line.
TerminalProgress::~TerminalProgress() {
  if (!finished_ && drawn_) std::fputc('\n', stderr);
}

// "\r\033[K": back to the start of the line and erase it, so a shorter line leaves nothing behind.
void TerminalProgress::Update(int done, const std::string& detail) {
  done_ = done;
  if (!interactive_) return;
  const auto now = std::chrono::steady_clock::now();
  if (drawn_ && now - last_draw_ < std::chrono::milliseconds(200)) return;
  last_draw_ = now;
  drawn_ = true;
  const double seconds = std::chrono::duration<double>(now - start_).count();
  const double rate = seconds > 0 ? done / seconds : 0;
  const std::string more = detail.empty() ? "" : "  " + detail;
  if (total_ && *total_ > 0 && done < *total_) {
    const double left = rate > 0 ? (*total_ - done) / rate : 0;
    std::fprintf(stderr, "\r\033[K%s: %d/%d frames  %.1f fps  %.0f s left%s", label_.c_str(),
                 done, *total_, rate, left, more.c_str());
  } else {
    std::fprintf(stderr, "\r\033[K%s: %d frames  %.1f fps%s", label_.c_str(), done, rate,
                 more.c_str());
  }
  std::fflush(stderr);
}

void TerminalProgress::Finish() {
  if (finished_) return;
  finished_ = true;
  if (!interactive_) return;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "\r\033[K%s: %d frames in %.1f s (%.1f fps, the whole run)\n",
               label_.c_str(), done_, seconds, seconds > 0 ? done_ / seconds : 0.0);
}

void ShowProgressOnTerminal() {
  SetProgressDisplay([](const std::string& label, std::optional<int> total) {
    return std::make_unique<TerminalProgress>(label, total);
  });
}

}  // namespace gf
