#include "apps/interrupt.h"

#include <csignal>

namespace gf {
namespace {

std::atomic<int> g_signal{0};
using Handler = void (*)(int);
Handler g_previous_int = SIG_DFL, g_previous_term = SIG_DFL;

extern "C" void OnSignal(int signal) {
  g_signal = signal;
  // A second Ctrl-C is the user insisting: the default action ends the process.
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
}

}  // namespace

InterruptHandler::InterruptHandler() {
  g_signal = 0;
  g_previous_int = std::signal(SIGINT, OnSignal);
  g_previous_term = std::signal(SIGTERM, OnSignal);
}

InterruptHandler::~InterruptHandler() {
  std::signal(SIGINT, g_previous_int == SIG_ERR ? SIG_DFL : g_previous_int);
  std::signal(SIGTERM, g_previous_term == SIG_ERR ? SIG_DFL : g_previous_term);
}

const std::atomic<int>* InterruptHandler::signal() const { return &g_signal; }

std::string SignalName(int signal) {
  if (signal == SIGINT) return "SIGINT";
  if (signal == SIGTERM) return "SIGTERM";
  return "signal " + std::to_string(signal);
}

}  // namespace gf
