#pragma once
/// \file
/// A fixed set of worker threads that an Extractor keeps for its lifetime, so that spreading the
/// views over threads costs no thread creation (and no allocation) per frame.

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace affine_orb::detail {

/// `threads − 1` worker threads plus the calling thread run the calls fn(i, w) for every i in
/// [0, n) of one run(); w in [0, threads) numbers the thread (per-thread buffers). Indices are
/// handed out in increasing order as threads become free. One run() at a time: the pool belongs to
/// one Extractor, which must not be used by two threads at once.
class WorkerPool {
 public:
  explicit WorkerPool(int threads) : errors_(static_cast<std::size_t>(std::max(threads, 1))) {
    for (int w = 1; w < threads; ++w) workers_.emplace_back([this, w] { serve(w); });
  }

  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  ~WorkerPool() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : workers_) t.join();
  }

  /// Number of threads taking part in a run, the calling thread included.
  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  /// Runs fn(i, w) for every i in [0, n) and returns when all calls have finished; rethrows the
  /// first exception (by thread number) that a call threw, after the others have stopped taking
  /// new indices.
  template <class Fn>
  void run(int n, Fn& fn) {
    if (workers_.empty() || n <= 1) {
      for (int i = 0; i < n; ++i) fn(i, 0);
      return;
    }
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      job_ = &fn;
      call_ = [](void* job, int i, int w) { (*static_cast<Fn*>(job))(i, w); };
      n_ = n;
      next_ = 0;
      busy_ = static_cast<int>(workers_.size());
      ++generation_;
    }
    wake_.notify_all();
    work(0);
    {
      std::unique_lock<std::mutex> lock(mutex_);
      done_.wait(lock, [this] { return busy_ == 0; });
    }
    for (std::exception_ptr& e : errors_) {
      if (e) {
        const std::exception_ptr first = e;
        for (std::exception_ptr& other : errors_) other = nullptr;
        std::rethrow_exception(first);
      }
    }
  }

 private:
  /// Takes indices of the current job until none is left.
  void work(int w) {
    try {
      for (int i = next_++; i < n_; i = next_++) call_(job_, i, w);
    } catch (...) {
      errors_[static_cast<std::size_t>(w)] = std::current_exception();
      next_ = n_;
    }
  }

  /// Worker w: waits for each new job, works on it, reports when done.
  void serve(int w) {
    unsigned long seen = 0;
    for (;;) {
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
        if (stop_) return;
        seen = generation_;
      }
      work(w);
      {
        const std::lock_guard<std::mutex> lock(mutex_);
        --busy_;
      }
      done_.notify_one();
    }
  }

  std::vector<std::thread> workers_;
  std::vector<std::exception_ptr> errors_;  ///< per thread: what its calls threw
  std::mutex mutex_;
  std::condition_variable wake_;  ///< a new job, or stop
  std::condition_variable done_;  ///< a worker finished the job
  void* job_ = nullptr;
  void (*call_)(void*, int, int) = nullptr;
  int n_ = 0;
  std::atomic<int> next_{0};
  int busy_ = 0;  ///< workers still on the current job
  unsigned long generation_ = 0;
  bool stop_ = false;
};

/// Runs fn(i, w) for every i in [0, n) on `threads` threads, the calling thread included: in order
/// on the calling thread when threads <= 1 or n <= 1, else on `pool`, which it starts on first use
/// and keeps for the later calls.
template <class Fn>
void run_indexed(std::unique_ptr<WorkerPool>& pool, int threads, int n, Fn fn) {
  if (threads <= 1 || n <= 1) {
    for (int i = 0; i < n; ++i) fn(i, 0);
    return;
  }
  if (!pool) pool = std::make_unique<WorkerPool>(threads);
  pool->run(n, fn);
}

}  // namespace affine_orb::detail
