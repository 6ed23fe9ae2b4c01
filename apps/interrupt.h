// Ctrl-C (SIGINT) and SIGTERM for long commands: while an InterruptHandler lives, the first such
// signal only sets a flag that the command polls (so it can stop cleanly and write what it has);
// a second one, a second or more later, ends the process at once.
//
// One handler at a time (it owns the process's signal dispositions); not thread-safe to create.
#pragma once

#include <atomic>

#include "acquisition/errors.h"  // Interrupted, SignalName

namespace gf {

class InterruptHandler {
 public:
  InterruptHandler();
  ~InterruptHandler();  // restores the dispositions found at construction
  InterruptHandler(const InterruptHandler&) = delete;
  InterruptHandler& operator=(const InterruptHandler&) = delete;
  // The signal received (SIGINT, SIGTERM), 0 while none; safe to read from any thread.
  const std::atomic<int>* signal() const;
};

}  // namespace gf
