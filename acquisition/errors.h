// Error kinds shared by every GlassFusion module.
//
// DESIGN.md names three kinds of failure:
//  - bad configuration: an Options struct's Check() returns false with a message;
//  - broken precondition (a programming error): GF_CHECK throws std::logic_error with file:line;
//  - bad user input (missing file, corrupt image, wrong depth scale ...): InputError, whose message
//  is
//    one line "<file>: <problem>". The command line prints it and exits with code 2.
// Expected algorithmic failures (tracking lost, too few inliers) are statuses in result structs,
// never exceptions.
#pragma once

#include <stdexcept>
#include <string>

namespace gf {

// Bad input from the user or from disk. what() is "<file>: <problem>" on one line.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, const std::string& problem);
  const std::string& file() const { return file_; }
  const std::string& problem() const { return problem_; }

 private:
  std::string file_;
  std::string problem_;
};

// A run stopped by a signal (Ctrl-C, SIGTERM) after writing what it had; the command line exits
// with 128 + signal.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal, const std::string& message)
      : std::runtime_error(message), signal_(signal) {}
  int signal() const { return signal_; }

 private:
  int signal_;
};

// "SIGINT", "SIGTERM" or "signal N".
std::string SignalName(int signal);

namespace internal {
[[noreturn]] void FailCheck(const char* condition, const char* file, int line,
                            const std::string& message);
}  // namespace internal

}  // namespace gf

// Precondition check for programming errors; throws std::logic_error naming file:line.
#define GF_CHECK(condition, message)                                                      \
  do {                                                                                    \
    if (!(condition)) ::gf::internal::FailCheck(#condition, __FILE__, __LINE__, message); \
  } while (0)
