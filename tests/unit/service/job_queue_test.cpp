// JobQueue on its own: ordering, the --max-queued bound, removal (cancel of a
// queued bake), close() (shutdown) and concurrent use. No daemon, no device.
//
// The queue holds only bakes that wait. How many bakes run at once
// (--max-concurrent-bakes) and cancelling a running bake are BakeRunner's
// work, not the queue's; a bake that a worker has popped is no longer here.
#include "service/job_queue.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <set>
#include <string>
#include <thread>
#include <vector>

namespace luxel::service {
namespace {

using namespace std::chrono_literals;

// A pop() that cannot hang the test: the answer, or "<timeout>".
std::string pop_within(JobQueue& q, std::chrono::milliseconds limit = 5s) {
  auto f = std::async(std::launch::async, [&q] { return q.pop(); });
  if (f.wait_for(limit) != std::future_status::ready) {
    q.close();  // lets the stuck pop() return so the future can be destroyed
    return "<timeout>";
  }
  auto id = f.get();
  return id ? *id : "<closed>";
}

std::vector<std::string> drain(JobQueue& q) {
  std::vector<std::string> out;
  while (q.size() > 0) {
    out.push_back(pop_within(q));
    if (out.back().front() == '<') break;  // closed or stuck: never loop forever
  }
  return out;
}

TEST(JobQueue, HigherPriorityFirst) {
  JobQueue q(10);
  ASSERT_TRUE(q.push("low", -3, 1).is_ok());
  ASSERT_TRUE(q.push("mid", 0, 2).is_ok());
  ASSERT_TRUE(q.push("high", 7, 3).is_ok());
  ASSERT_TRUE(q.push("mid2", 0, 4).is_ok());
  EXPECT_EQ(drain(q), (std::vector<std::string>{"high", "mid", "mid2", "low"}));
}

TEST(JobQueue, FifoWithinAPriorityBySequenceNumber) {
  JobQueue q(10);
  // Pushed out of order (as startup recovery may): the sequence number decides.
  ASSERT_TRUE(q.push("third", 1, 30).is_ok());
  ASSERT_TRUE(q.push("first", 1, 10).is_ok());
  ASSERT_TRUE(q.push("second", 1, 20).is_ok());
  EXPECT_EQ(drain(q), (std::vector<std::string>{"first", "second", "third"}));
}

TEST(JobQueue, PriorityBeatsAge) {
  JobQueue q(10);
  ASSERT_TRUE(q.push("old", 0, 1).is_ok());
  ASSERT_TRUE(q.push("new_urgent", 1, 100).is_ok());
  EXPECT_EQ(pop_within(q), "new_urgent");
  EXPECT_EQ(pop_within(q), "old");
}

TEST(JobQueue, FullQueueRejectsWithResourceExhaustedNamingTheFlag) {
  JobQueue q(2);
  EXPECT_TRUE(q.check_room().is_ok());
  ASSERT_TRUE(q.push("a", 0, 1).is_ok());
  ASSERT_TRUE(q.push("b", 0, 2).is_ok());
  const Status room = q.check_room();
  EXPECT_EQ(room.code(), StatusCode::kResourceExhausted);
  const Status st = q.push("c", 0, 3);
  EXPECT_EQ(st.code(), StatusCode::kResourceExhausted);
  EXPECT_NE(st.message().find("--max-queued=2"), std::string::npos) << st.message();
  EXPECT_EQ(q.size(), 2u);
  // A pop makes room again.
  EXPECT_EQ(pop_within(q), "a");
  EXPECT_TRUE(q.check_room().is_ok());
  EXPECT_TRUE(q.push("c", 0, 3).is_ok());
  EXPECT_EQ(drain(q), (std::vector<std::string>{"b", "c"}));
}

TEST(JobQueue, ForcedPushIgnoresTheLimit) {
  // Bakes re-queued at startup were accepted before and must not be dropped.
  JobQueue q(1);
  ASSERT_TRUE(q.push("a", 0, 1).is_ok());
  EXPECT_TRUE(q.push("b", 0, 2, /*force=*/true).is_ok());
  EXPECT_TRUE(q.push("c", 5, 3, /*force=*/true).is_ok());
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(q.push("d", 0, 4).code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(drain(q), (std::vector<std::string>{"c", "a", "b"}));
}

TEST(JobQueue, ZeroLimitAcceptsOnlyForcedPushes) {
  JobQueue q(0);
  EXPECT_EQ(q.check_room().code(), StatusCode::kResourceExhausted);
  EXPECT_EQ(q.push("a", 0, 1).code(), StatusCode::kResourceExhausted);
  EXPECT_TRUE(q.push("a", 0, 1, true).is_ok());
  EXPECT_EQ(q.size(), 1u);
}

TEST(JobQueue, RemoveTakesOutAQueuedJob) {
  JobQueue q(10);
  ASSERT_TRUE(q.push("a", 0, 1).is_ok());
  ASSERT_TRUE(q.push("b", 9, 2).is_ok());
  ASSERT_TRUE(q.push("c", 0, 3).is_ok());
  EXPECT_TRUE(q.remove("b"));
  EXPECT_FALSE(q.remove("b")) << "removed twice";
  EXPECT_FALSE(q.remove("nope"));
  EXPECT_EQ(q.size(), 2u);
  EXPECT_EQ(drain(q), (std::vector<std::string>{"a", "c"}));
}

TEST(JobQueue, RemoveOfAPoppedJobReportsNotQueued) {
  // Once a worker has popped a bake, cancelling it is the runner's business:
  // remove() must say so rather than pretend it cancelled something.
  JobQueue q(10);
  ASSERT_TRUE(q.push("running", 0, 1).is_ok());
  ASSERT_TRUE(q.push("waiting", 0, 2).is_ok());
  EXPECT_EQ(pop_within(q), "running");
  EXPECT_FALSE(q.remove("running"));
  EXPECT_EQ(q.size(), 1u);
}

TEST(JobQueue, PopBlocksUntilAJobArrives) {
  JobQueue q(10);
  auto f = std::async(std::launch::async, [&q] { return q.pop(); });
  EXPECT_EQ(f.wait_for(100ms), std::future_status::timeout) << "pop() returned on an empty queue";
  ASSERT_TRUE(q.push("late", 0, 1).is_ok());
  ASSERT_EQ(f.wait_for(5s), std::future_status::ready);
  auto id = f.get();
  ASSERT_TRUE(id.has_value());
  EXPECT_EQ(*id, "late");
}

TEST(JobQueue, CloseWakesEveryWaitingPop) {
  JobQueue q(10);
  std::vector<std::future<std::optional<std::string>>> waiting;
  for (int i = 0; i < 4; ++i)
    waiting.push_back(std::async(std::launch::async, [&q] { return q.pop(); }));
  std::this_thread::sleep_for(50ms);
  q.close();
  for (auto& f : waiting) {
    ASSERT_EQ(f.wait_for(5s), std::future_status::ready) << "a pop() stayed blocked after close()";
    EXPECT_FALSE(f.get().has_value());
  }
}

TEST(JobQueue, CloseKeepsWaitingJobsButHandsNoneOut) {
  // Shutdown while jobs wait: they stay queued (the records say QUEUED and the
  // next start re-queues them) and no worker gets one.
  JobQueue q(10);
  ASSERT_TRUE(q.push("a", 0, 1).is_ok());
  ASSERT_TRUE(q.push("b", 3, 2).is_ok());
  q.close();
  EXPECT_EQ(pop_within(q), "<closed>");
  EXPECT_EQ(q.size(), 2u);
  // Later pushes are still stored and accepted.
  EXPECT_TRUE(q.push("c", 0, 3).is_ok());
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(pop_within(q), "<closed>");
  EXPECT_TRUE(q.remove("a"));
}

TEST(JobQueue, ConcurrentProducersAndConsumersLoseNothing) {
  constexpr int kProducers = 6, kPerProducer = 300, kConsumers = 3;
  constexpr int kTotal = kProducers * kPerProducer;
  JobQueue q(kTotal);
  std::atomic<uint64_t> seq{1};
  std::mutex got_mu;
  std::multiset<std::string> got;
  std::vector<std::thread> consumers;
  for (int c = 0; c < kConsumers; ++c) {
    consumers.emplace_back([&] {
      while (auto id = q.pop()) {
        std::lock_guard<std::mutex> lock(got_mu);
        got.insert(*id);
      }
    });
  }
  std::vector<std::thread> producers;
  std::atomic<int> failures{0};
  for (int p = 0; p < kProducers; ++p) {
    producers.emplace_back([&, p] {
      for (int i = 0; i < kPerProducer; ++i) {
        const std::string id = std::to_string(p) + "-" + std::to_string(i);
        if (!q.push(id, i % 4, seq.fetch_add(1)).is_ok()) ++failures;
        if (i % 50 == 0) (void)q.remove("no-such-bake");  // contend on the lock too
      }
    });
  }
  for (auto& t : producers) t.join();
  // Bounded wait for the consumers to empty the queue.
  for (int i = 0; i < 500 && q.size() > 0; ++i) std::this_thread::sleep_for(10ms);
  q.close();
  for (auto& t : consumers) t.join();
  EXPECT_EQ(failures.load(), 0);
  EXPECT_EQ(q.size(), 0u);
  ASSERT_EQ(got.size(), static_cast<size_t>(kTotal));
  EXPECT_EQ(std::set<std::string>(got.begin(), got.end()).size(), got.size())
      << "a job was handed out twice";
}

TEST(JobQueue, ConcurrentSubmitsNeverExceedTheLimit) {
  // Many submitters race for the last places: exactly max_queued succeed.
  constexpr size_t kLimit = 40;
  constexpr int kThreads = 8, kPerThread = 50;
  for (int round = 0; round < 500; ++round) {
    JobQueue q(kLimit);
    std::atomic<uint64_t> seq{1};
    std::atomic<int> accepted{0};
    std::atomic<bool> go{false};
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&, t] {
        while (!go) std::this_thread::yield();
        for (int i = 0; i < kPerThread; ++i) {
          const Status st = q.push(std::to_string(t) + "-" + std::to_string(i), 0, seq++);
          if (st.is_ok()) {
            ++accepted;
          } else {
            EXPECT_EQ(st.code(), StatusCode::kResourceExhausted);
          }
        }
      });
    }
    go = true;
    for (auto& t : threads) t.join();
    ASSERT_EQ(q.size(), kLimit) << "round " << round;
    ASSERT_EQ(accepted.load(), static_cast<int>(kLimit)) << "round " << round;
  }
}

}  // namespace
}  // namespace luxel::service
