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
