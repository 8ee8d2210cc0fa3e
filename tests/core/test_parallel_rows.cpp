// Rows of work on all cores (core/parallel_rows.h).
#include <doctest/doctest.h>

#include <atomic>
#include <set>
#include <thread>
#include <vector>

#include "core/parallel_rows.h"

using namespace at;

TEST_CASE("ParallelRows_EveryRowRunsOnceAndAllAreDoneOnReturn") {
  for (int rows : {0, 1, 2, 7, 1000}) {
    CAPTURE(rows);
    std::vector<std::atomic<int>> runs(static_cast<std::size_t>(rows));
    std::vector<std::thread::id> by(static_cast<std::size_t>(rows));
    forEachRowInParallel(rows, [&](int row) {
      runs[std::size_t(row)]++;
      by[std::size_t(row)] = std::this_thread::get_id();
    });
    for (int row = 0; row < rows; ++row) CHECK(runs[std::size_t(row)] == 1);
    if (rows == 1000) {
      const std::set<std::thread::id> threads(by.begin(), by.end());
      CHECK(threads.size() <= std::max(1u, std::thread::hardware_concurrency()));
    }
  }
}

TEST_CASE("ParallelBlocks_CoverEveryItemOnceInContiguousBlocks_NoMoreThanAsked") {
  const int hardware = int(std::max(1u, std::thread::hardware_concurrency()));
  for (int n : {0, 1, 2, 7, 1000})
    for (int maxThreads : {0, 1, 3}) {
      CAPTURE(n);
      CAPTURE(maxThreads);
      std::vector<std::atomic<int>> runs(static_cast<std::size_t>(n));
      std::atomic<int> blocks{0};
      forEachBlockInParallel(
          n,
          [&](int begin, int end) {
            CHECK(0 <= begin);
            CHECK(begin < end);  // no empty block is handed out
            CHECK(end <= n);
            ++blocks;
            for (int i = begin; i < end; ++i) runs[std::size_t(i)]++;
          },
          maxThreads);
      for (int i = 0; i < n; ++i) CHECK(runs[std::size_t(i)] == 1);
      const int allowed = maxThreads > 0 ? std::min(maxThreads, hardware) : hardware;
      CHECK(blocks <= std::max(0, std::min(n, allowed)));
      if (n > 0) CHECK(blocks >= 1);
    }
}

TEST_CASE("ParallelRows_RunOnNoMoreThreadsThanAsked") {
  for (int maxThreads : {1, 2}) {
    CAPTURE(maxThreads);
    std::vector<std::thread::id> by(200);
    forEachRowInParallel(
        200, [&](int row) { by[std::size_t(row)] = std::this_thread::get_id(); }, maxThreads);
    const std::set<std::thread::id> threads(by.begin(), by.end());
    CHECK(threads.size() <= std::size_t(maxThreads));
    if (maxThreads == 1) CHECK(*threads.begin() == std::this_thread::get_id());
  }
}
