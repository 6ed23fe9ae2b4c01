#include "acquisition/errors.h"

#include <algorithm>
#include <csignal>
#include <sstream>

namespace gf {
namespace {
// Keep the message on one line whatever the caller passed in.
std::string OneLine(std::string s) {
  std::replace(s.begin(), s.end(), '\n', ' ');
  std::replace(s.begin(), s.end(), '\r', ' ');
  return s;
}
}  // namespace

InputError::InputError(const std::string& file, const std::string& problem)
    : std::runtime_error(OneLine(file + ": " + problem)), file_(file), problem_(problem) {}

std::string SignalName(int signal) {
  if (signal == SIGINT) return "SIGINT";
  if (signal == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal);
}

namespace internal {
void FailCheck(const char* condition, const char* file, int line, const std::string& message) {
  std::ostringstream out;
  out << file << ":" << line << ": check failed: " << condition;
  if (!message.empty()) out << ": " << message;
  throw std::logic_error(out.str());
}
}  // namespace internal
}  // namespace gf
