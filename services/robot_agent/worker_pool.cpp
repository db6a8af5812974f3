#include "worker_pool.hpp"

namespace fleet::agent {

WorkerPool::WorkerPool(unsigned threads) {
  for (unsigned i = 1; i < threads; ++i) {
    workers_.emplace_back([this] { work(); });
  }
}

WorkerPool::~WorkerPool() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
  }
  wake_.notify_all();
  for (auto& t : workers_) {
    t.join();
  }
}

void WorkerPool::drain(std::size_t n, const std::function<void(std::size_t)>* fn) {
  std::size_t mine = 0;
  for (std::size_t i = next_.fetch_add(1); i < n; i = next_.fetch_add(1)) {
    (*fn)(i);
    ++mine;
  }
  std::lock_guard lock(m_);
  finished_ += mine;
  done_.notify_all();
}

void WorkerPool::work() {
  std::uint64_t seen = 0;
  for (;;) {
    std::size_t n = 0;
    const std::function<void(std::size_t)>* fn = nullptr;
    {
      std::unique_lock lock(m_);
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) {
        return;
      }
      seen = generation_;
      n = n_;
      fn = fn_;
      ++active_;
    }
    drain(n, fn);  // a late worker of a finished call claims nothing and never calls fn
    std::lock_guard lock(m_);
    --active_;
    done_.notify_all();
  }
}

void WorkerPool::forEach(std::size_t n, const std::function<void(std::size_t)>& fn) {
  if (n == 0) {
    return;
  }
  if (workers_.empty()) {
    for (std::size_t i = 0; i < n; ++i) {
      fn(i);
    }
    return;
  }
  {
    std::unique_lock lock(m_);
    // A worker still inside the previous call's drain would claim from the reset counter.
    done_.wait(lock, [&] { return active_ == 0; });
    fn_ = &fn;
    n_ = n;
    finished_ = 0;
    next_.store(0);
    ++generation_;
  }
  wake_.notify_all();
  drain(n, &fn);
  std::unique_lock lock(m_);
  // Every index done, and no worker still holds `fn` (it lives in the caller's frame).
  done_.wait(lock, [&] { return finished_ == n && active_ == 0; });
}

}  // namespace fleet::agent
