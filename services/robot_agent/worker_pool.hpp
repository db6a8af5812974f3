#pragma once

// A fixed pool of threads running one parallel-for at a time: forEach(n, fn) calls fn(0..n-1), each
// index exactly once, spread over the workers and the calling thread, and returns when all are done.
// The agents of a process are stepped this way each cycle; each agent's state is its own, so the
// order in which they run cannot change what they compute.

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace fleet::agent {

class WorkerPool {
 public:
  /// `threads` in total including the caller (1: everything runs on the caller, no threads made).
  explicit WorkerPool(unsigned threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  void forEach(std::size_t n, const std::function<void(std::size_t)>& fn);
  [[nodiscard]] unsigned threads() const { return static_cast<unsigned>(workers_.size()) + 1; }

 private:
  void work();
  /// Claims and runs indices of the current call; `n`, `fn` copied under the lock.
  void drain(std::size_t n, const std::function<void(std::size_t)>* fn);

  std::vector<std::thread> workers_;
  std::mutex m_;
  std::condition_variable wake_;
  std::condition_variable done_;
  const std::function<void(std::size_t)>* fn_ = nullptr;
  std::size_t n_ = 0;
  std::atomic<std::size_t> next_{0};
  std::size_t finished_ = 0;  // indices completed (under m_)
  unsigned active_ = 0;       // workers inside drain (under m_): a call starts only at 0
  std::uint64_t generation_ = 0;
  bool stop_ = false;
};

}  // namespace fleet::agent
