// cl::DeviceTurns (issue 51): one slice on the device at a time, the next turn to the waiting
// client that has used the least device time over its weight. No OpenCL: turns are host logic.
#include "engine/cl/device_turns.hpp"

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace shadow::cl {
namespace {

// Waits until `n` turns are asked for beyond the one held (a waiter shows in usage()'s account
// only through the order it gets; so poll a counter the waiters set just before asking).
void wait_for(const std::atomic<int>& asked, int n) {
  while (asked.load() < n) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // they are inside take() now
}

// While one client holds the device, clients wait; the order they get it in.
std::vector<std::string> order_of(DeviceTurns& turns, const std::vector<std::string>& waiters) {
  turns.take("holder", &turns);
  std::vector<std::string> order;
  std::mutex m;
  std::atomic<int> asked{0};
  std::vector<std::thread> threads;
  for (const std::string& client : waiters) {
    threads.emplace_back([&, client] {
      ++asked;
      turns.take(client, &client);
      {
        std::lock_guard<std::mutex> lock(m);
        order.push_back(client);
      }
      turns.give(client, 0);
    });
    wait_for(asked, int(threads.size()));  // in the order listed
  }
  turns.give("holder", 0);
  for (std::thread& t : threads) t.join();
  return order;
}

TEST(DeviceTurns, TheLeastUsedClientGoesFirstThenFirstComeFirstServed) {
  DeviceTurns turns;
  turns.enter("heavy");
  turns.enter("light");
  turns.take("heavy", nullptr);
  turns.give("heavy", 500);  // heavy has used 500 ms
  EXPECT_EQ(order_of(turns, {"heavy", "light"}), (std::vector<std::string>{"light", "heavy"}));
  // Equals keep their order of arrival.
  DeviceTurns fresh;
  EXPECT_EQ(order_of(fresh, {"a", "b", "c"}), (std::vector<std::string>{"a", "b", "c"}));
}

TEST(DeviceTurns, WeightsDivideTheUsage) {
  DeviceTurns turns;
  turns.set_weights({{"big", 4.0}});
  turns.enter("big");
  turns.enter("small");
  turns.take("big", nullptr);
  turns.give("big", 300);  // 75 weighted
  turns.take("small", nullptr);
  turns.give("small", 100);  // 100 weighted
  EXPECT_DOUBLE_EQ(turns.usage("big"), 75);
  EXPECT_EQ(order_of(turns, {"small", "big"}), (std::vector<std::string>{"big", "small"}));
}

TEST(DeviceTurns, AReturningClientStartsNearTheLeastUsedAtWork) {
  DeviceTurns turns;
  turns.enter("steady");
  turns.take("steady", nullptr);
  turns.give("steady", 10000);
  // A newcomer starts at the floor: the least usage of those at work, not at 0.
  EXPECT_DOUBLE_EQ(turns.usage("newcomer"), 10000);
  // A client that used much, left, and came back starts at most kMemoryMs above the floor.
  turns.enter("old");
  turns.take("old", nullptr);
  turns.give("old", 50000);
  turns.leave("old");
  turns.enter("old");
  EXPECT_DOUBLE_EQ(turns.usage("old"), 10000 + DeviceTurns::kMemoryMs);
  // Its total stays for the statistics, the most used first.
  const std::vector<DeviceTurns::Total> totals = turns.totals();
  ASSERT_EQ(totals.size(), 2u);
  EXPECT_EQ(totals[0].client, "old");
  EXPECT_DOUBLE_EQ(totals[0].ms, 50000);
  EXPECT_DOUBLE_EQ(totals[1].ms, 10000);
}

TEST(DeviceTurns, OneSliceAtATime) {
  DeviceTurns turns;
  std::atomic<int> on_device{0}, most{0};
  std::vector<std::thread> threads;
  for (int c = 0; c < 4; ++c)
    threads.emplace_back([&, c] {
      for (int i = 0; i < 50; ++i) {
        turns.take("client" + std::to_string(c), &turns);
        most = std::max(most.load(), ++on_device);
        std::this_thread::sleep_for(std::chrono::microseconds(100));
        --on_device;
        turns.give("client" + std::to_string(c), 0.1);
      }
    });
  for (std::thread& t : threads) t.join();
  EXPECT_EQ(most.load(), 1);
}

// A queue may queue a second command behind its own running one while no waiting client has
// used less, never behind another's; and a client that waits keeps the device from it.
TEST(DeviceTurns, AQueueQueuesBehindItsOwnCommandOnlyWhileItIsAhead) {
  DeviceTurns turns;
  int a = 0, b = 0;  // two queues' identities
  turns.take("x", &a);
  EXPECT_FALSE(turns.take_behind("x", &b)) << "behind another queue's command";
  EXPECT_TRUE(turns.take_behind("x", &a));
  EXPECT_FALSE(turns.take_behind("x", &a)) << "two are the most";
  turns.give("x", 10);
  turns.give("x", 10);
  // A client that has used less waits: no queuing behind any more.
  std::atomic<bool> served{false};
  turns.take("x", &a);
  std::thread waiter([&] {
    turns.take("y", &b);
    served = true;
    turns.give("y", 1);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // y is waiting now
  EXPECT_FALSE(turns.take_behind("x", &a));
  turns.give("x", 10);
  waiter.join();
  EXPECT_TRUE(served);
}

}  // namespace
}  // namespace shadow::cl
