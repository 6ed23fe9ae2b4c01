// The thread a pipeline stage owns: it runs the stage's body once, keeps what the body threw (a
// stage contains its own per-frame failures; what escapes is what stops the run), and tells
// waiters when it has ended.
//
// Thread-safety: Start, WaitFor, Join and error from the owning thread.
#pragma once

#include <chrono>
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>

namespace gf {

class StageThread {
 public:
  StageThread() = default;
  ~StageThread() { Join(); }
  StageThread(const StageThread&) = delete;
  StageThread& operator=(const StageThread&) = delete;

  void Start(std::function<void()> body) {
    thread_ = std::thread([this, body = std::move(body)] {
      try {
        body();
      } catch (...) {
        error_ = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex_);
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

 private:
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable ended_cv_;
  bool ended_ = false;
  std::exception_ptr error_;
};

}  // namespace gf
