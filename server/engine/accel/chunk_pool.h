// Threads that share a loop's chunks, kept for the owner's life, so a ray
// query starts no thread. The Embree backend answers each bounce of each
// iteration with one query per kind (closest, any): before this pool every
// query started and joined its own threads, and on small lightmaps a query's
// last bounces held fewer rays than one chunk, so the thread it started had
// nothing to do (docs/performance.md, "Fixed costs per iteration").
//
//   ChunkPool pool(0);  // hardware_concurrency() - 1 helpers
//   pool.run(n, 4096, 0, [&](size_t begin, size_t end) { ... });
#pragma once

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace luxel::accel {

class ChunkPool {
 public:
  // `threads` threads in all, the caller's included (0: one per core).
  explicit ChunkPool(unsigned threads) {
    if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
    for (unsigned i = 0; i + 1 < threads; ++i) helpers_.emplace_back([this, i] { serve(i); });
  }
  ~ChunkPool() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      stop_ = true;
    }
    wake_.notify_all();
    for (std::thread& t : helpers_) t.join();
  }
  ChunkPool(const ChunkPool&) = delete;
  ChunkPool& operator=(const ChunkPool&) = delete;

  // fn(begin, end) over [0, n) in chunks of `chunk`, on at most `threads`
  // threads (0: all of the pool's), the caller's among them; returns when
  // every chunk is done. A loop of one chunk runs on the caller alone. Runs
  // from several threads take turns.
  void run(size_t n, size_t chunk, unsigned threads,
           const std::function<void(size_t, size_t)>& fn) const {
    const size_t chunks = (n + chunk - 1) / chunk;
    const size_t wanted = std::min<size_t>(threads == 0 ? helpers_.size() + 1 : threads, chunks);
    const unsigned helpers =
        static_cast<unsigned>(std::min(helpers_.size(), wanted - std::min<size_t>(wanted, 1)));
    if (helpers == 0) {
      for (size_t b = 0; b < n; b += chunk) fn(b, std::min(n, b + chunk));
      return;
    }
    std::lock_guard<std::mutex> turn(turn_);
    {
      std::lock_guard<std::mutex> lock(mu_);
      job_ = {n, chunk, &fn, helpers};
      next_.store(0);
      busy_ = helpers;
      ++generation_;
    }
    wake_.notify_all();
    work();
    std::unique_lock<std::mutex> lock(mu_);
    done_.wait(lock, [this] { return busy_ == 0; });
  }

 private:
  struct Job {
    size_t n = 0, chunk = 1;
    const std::function<void(size_t, size_t)>* fn = nullptr;
    unsigned helpers = 0;  // helpers 0 .. helpers - 1 take part
  };

  void work() const {
    for (;;) {
      const size_t begin = next_.fetch_add(job_.chunk);
      if (begin >= job_.n) return;
      (*job_.fn)(begin, std::min(job_.n, begin + job_.chunk));
    }
  }

  void serve(unsigned index) const {
    uint64_t seen = 0;
    std::unique_lock<std::mutex> lock(mu_);
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      if (index >= job_.helpers) continue;
      lock.unlock();
      work();
      lock.lock();
      if (--busy_ == 0) done_.notify_one();
    }
  }

  std::vector<std::thread> helpers_;
  mutable std::mutex turn_;  // one run at a time
  mutable std::mutex mu_;    // guards job_, busy_, generation_, stop_
  mutable std::condition_variable wake_, done_;
  mutable Job job_;
  mutable std::atomic<size_t> next_{0};
  mutable unsigned busy_ = 0;
  mutable uint64_t generation_ = 0;
  bool stop_ = false;
};

}  // namespace luxel::accel
