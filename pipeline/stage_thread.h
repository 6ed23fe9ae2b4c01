// The thread a pipeline stage owns: it runs the stage's body once, keeps what the body threw (a
// stage contains its own per-frame failures; what escapes is what stops the run), and tells
// waiters when it has ended. It carries the stage's name (the thread's name in `top -H`, `perf`
// and gdb) and measures the CPU time the thread itself used: work a stage hands to OpenCV's worker
// pool is counted there, not here.
//
// Thread-safety: Start, WaitFor, Join and error from the owning thread.
#pragma once

#include <pthread.h>
#include <time.h>

#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace gf {

class StageThread {
 public:
  StageThread() = default;
  ~StageThread() { Join(); }
  StageThread(const StageThread&) = delete;
  StageThread& operator=(const StageThread&) = delete;

  // `name`: at most 15 characters show (the kernel's limit).
  void Start(const std::string& name, std::function<void()> body) {
    thread_ = std::thread([this, name, body = std::move(body)] {
      pthread_setname_np(pthread_self(), name.substr(0, 15).c_str());
      try {
        body();
      } catch (...) {
        error_ = std::current_exception();
      }
      const double cpu = ThreadCpuSeconds();
      std::lock_guard<std::mutex> lock(mutex_);
      cpu_seconds_ = cpu;
      ended_ = true;
      ended_cv_.notify_all();
    });
  }
  // True once the body has ended (waits at most `timeout`).
  bool WaitFor(std::chrono::milliseconds timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    return ended_cv_.wait_for(lock, timeout, [&] { return ended_; });
  }
  void Join() {
    if (thread_.joinable()) thread_.join();
  }
  // What the body threw, once it has ended (null when it returned).
  std::exception_ptr error() const { return error_; }
  // CPU seconds the thread used, once it has ended (0 before).
  double cpu_seconds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cpu_seconds_;
  }
  // CPU seconds the calling thread has used so far.
  static double ThreadCpuSeconds() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
  }

 private:
  std::thread thread_;
  mutable std::mutex mutex_;
  std::condition_variable ended_cv_;
  bool ended_ = false;
  double cpu_seconds_ = 0;
  std::exception_ptr error_;
};

}  // namespace gf
