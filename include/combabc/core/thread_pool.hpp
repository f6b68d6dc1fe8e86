#pragma once
// A fixed-size pool of worker threads that runs index-parallel loops. Work is handed out in
// chunks from an atomic counter; callers write results by index, so completion order never
// influences results (determinism is the caller's invariant, not the scheduler's).
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace combabc {

class ThreadPool {
 public:
  // threads = 0 means std::thread::hardware_concurrency(). threads = 1 runs inline.
  explicit ThreadPool(int threads = 1);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  int size() const { return size_; }

  // Calls body(begin, end) over [0, n) split into chunks of at most `chunk` indices; blocks until
  // all are done. The first exception thrown by body is rethrown here (the rest of the loop is
  // still drained so no worker touches freed state).
  void ParallelFor(std::size_t n,
                   std::size_t chunk,
                   const std::function<void(std::size_t, std::size_t)>& body);

 private:
  void WorkerLoop();
  void RunChunks();

  int size_;
  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::condition_variable done_;
  bool stop_ = false;
  std::size_t generation_ = 0;
  // Current job, valid while active_ > 0.
  const std::function<void(std::size_t, std::size_t)>* body_ = nullptr;
  std::size_t n_ = 0;
  std::size_t chunk_ = 1;
  std::size_t next_ = 0;
  int active_ = 0;
  std::exception_ptr error_;
};

}  // namespace combabc
