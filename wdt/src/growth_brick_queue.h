// The CPU growth engine's queue of bricks waiting for a visit (label_growth_cpu.cpp). Internal to
// at_wdt.
#pragma once

#include <atomic>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <queue>
#include <utility>
#include <vector>

#include "growth_brick_box.h"

namespace at::growth_cpu {

// The bricks waiting for a visit, smallest key first: a brick's key is the smallest distance among
// the changed voxels that queued it, so the front is worked from the seeds outwards (brick-level
// Dijkstra) and a brick is mostly visited once its surroundings have settled. The GPU runs rounds
// over every queued brick instead; on a few cores the order saves visits (measured at 128³:
// 5.3 visits a brick in rounds, bench/RESULTS.md). A brick being visited is not handed out again:
// one queued during its visit is queued again when the visit ends, so it always sees the stores
// that queued it (the mutex orders them). One lock per visit (~0.1 ms of work).
class BrickQueue {
 public:
  explicit BrickQueue(std::size_t bricks) : key_(bricks, kInf), again_(bricks, kInf), running_(bricks, 0) {}

  // Queues the bricks of `items` (brick, key) or lowers their keys.
  void push(const std::vector<std::pair<int, Dist>>& items) {
    if (items.empty()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [b, key] : items) pushLocked(b, key);
    }
    wake_.notify_all();
  }

  // The next brick to visit, or −1 once nothing is queued and no visit runs, or when *cancel is
  // set (queued bricks then stay queued).
  int pop(const std::atomic<bool>* cancel, bool& cancelled) {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      if (cancel && cancel->load(std::memory_order_relaxed)) {
        cancelled = !heap_.empty() || running_count_ > 0;
        return -1;
      }
      while (!heap_.empty()) {
        const auto [key, b] = heap_.top();
        heap_.pop();
        if (key != key_[std::size_t(b)]) continue;  // an older entry of a brick whose key went down
        key_[std::size_t(b)] = kInf;
        running_[std::size_t(b)] = 1;
        ++running_count_;
        return b;
      }
      if (running_count_ == 0) return -1;
      wake_.wait(lock);
    }
  }

  // Ends the visit of b (and queues it again if it was queued meanwhile).
  void finish(int b) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      running_[std::size_t(b)] = 0;
      --running_count_;
      if (again_[std::size_t(b)] < kInf) {
        pushLocked(b, again_[std::size_t(b)]);
        again_[std::size_t(b)] = kInf;
      }
    }
    wake_.notify_all();
  }

  bool empty() const { return heap_.empty(); }

 private:
  void pushLocked(int b, Dist key) {
    const std::size_t i = std::size_t(b);
    if (running_[i]) {
      again_[i] = std::min(again_[i], key);
    } else if (key < key_[i]) {
      key_[i] = key;
      heap_.push({key, b});
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::priority_queue<std::pair<Dist, int>, std::vector<std::pair<Dist, int>>, std::greater<>> heap_;
  std::vector<Dist> key_;    // kInf when not queued
  std::vector<Dist> again_;  // key to queue with when the running visit ends
  std::vector<char> running_;
  int running_count_ = 0;
};

}  // namespace at::growth_cpu
