// The ray queries' thread pool (accel/chunk_pool.h): every index of a loop
// is visited exactly once, whatever the loop's size, the threads asked for
// and the runs made from several threads at once; helpers take part.
#include "accel/chunk_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace luxel::accel {
namespace {

// Runs one loop and checks that [0, n) was covered exactly once.
void expect_each_index_once(const ChunkPool& pool, size_t n, size_t chunk, unsigned threads) {
  std::vector<std::atomic<int>> visits(n);
  pool.run(n, chunk, threads, [&](size_t begin, size_t end) {
    ASSERT_LT(begin, end);
    ASSERT_LE(end, n);
    for (size_t i = begin; i < end; ++i) visits[i].fetch_add(1);
  });
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(visits[i].load(), 1) << "index " << i << " of " << n;
}

TEST(ChunkPool, EveryIndexOnceAtAnySize) {
  const ChunkPool pool(4);
  for (size_t n :
       {size_t{0}, size_t{1}, size_t{63}, size_t{64}, size_t{65}, size_t{1000}, size_t{4099}})
    for (unsigned threads : {0u, 1u, 2u, 7u}) expect_each_index_once(pool, n, 64, threads);
}

TEST(ChunkPool, HelpersTakePartInLargeLoops) {
  const ChunkPool pool(3);
  std::mutex mu;
  std::condition_variable cv;
  std::set<std::thread::id> ids;
  // Every chunk waits until a second thread has taken one: only a helper can
  // end the wait (the 30-s bound only keeps a broken pool from hanging).
  pool.run(8, 1, 0, [&](size_t, size_t) {
    std::unique_lock<std::mutex> lock(mu);
    ids.insert(std::this_thread::get_id());
    cv.notify_all();
    cv.wait_for(lock, std::chrono::seconds(30), [&] { return ids.size() > 1; });
  });
  EXPECT_GT(ids.size(), 1u);
  // One chunk runs on the caller alone.
  ids.clear();
  pool.run(10, 64, 0, [&](size_t, size_t) {
    std::lock_guard<std::mutex> lock(mu);
    ids.insert(std::this_thread::get_id());
  });
  EXPECT_EQ(ids, std::set<std::thread::id>{std::this_thread::get_id()});
}

TEST(ChunkPool, RunsFromSeveralThreadsTakeTurns) {
  const ChunkPool pool(2);
  std::vector<std::thread> callers;
  for (int c = 0; c < 4; ++c)
    callers.emplace_back([&] {
      for (int r = 0; r < 50; ++r) expect_each_index_once(pool, 5000 + size_t(r), 128, 0);
    });
  for (std::thread& t : callers) t.join();
}

}  // namespace
}  // namespace luxel::accel
