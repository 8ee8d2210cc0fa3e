// Work split into rows (of an image, of a picture's pixels, of a volume's slices) run on all cores.
#pragma once

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

namespace at {

// Calls rowBody(row) once for every row in [0, rows), the rows handed out one at a time to up to
// hardware_concurrency threads (the calling thread among them), so that costly rows and cheap rows
// share the cores evenly. rowBody may write only what belongs to its row and must not throw;
// whatever the caller then gathers row by row, in row order, is the same as one thread would have
// made. Returns when every row is done.
template <class RowBody>
void forEachRowInParallel(int rows, const RowBody& rowBody) {
  const int threads = std::clamp(int(std::thread::hardware_concurrency()), 1, std::max(1, rows));
  std::atomic<int> next{0};
  const auto work = [&] {
    for (int row = next++; row < rows; row = next++) rowBody(row);
  };
  std::vector<std::jthread> helpers;
  helpers.reserve(std::size_t(threads - 1));
  for (int t = 1; t < threads; ++t) helpers.emplace_back(work);
  work();
}

}  // namespace at
