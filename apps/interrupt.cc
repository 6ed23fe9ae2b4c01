#include "apps/interrupt.h"

#include <csignal>
#include <ctime>

namespace gf {
namespace {

std::atomic<int> g_signal{0};
std::atomic<long long> g_first_ns{0};
using Handler = void (*)(int);
Handler g_previous_int = SIG_DFL, g_previous_term = SIG_DFL;

long long NowNs() {
  timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);  // async-signal-safe
  return t.tv_sec * 1000000000LL + t.tv_nsec;
}

extern "C" void OnSignal(int signal) {
  if (g_signal == 0) {
    g_first_ns = NowNs();
    g_signal = signal;
    return;
  }
  // A second signal a second or more after the first is the user insisting: the default action
  // ends the process. Sooner, it is the same signal delivered twice (timeout(1) and kill(1) send
  // it to the process and to its group).
  if (NowNs() - g_first_ns >= 1000000000LL) {
    std::signal(signal, SIG_DFL);
    std::raise(signal);
  }
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

}  // namespace gf
