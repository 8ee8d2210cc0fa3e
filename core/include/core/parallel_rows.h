// Work split into rows (of an image, of a picture's pixels, of a volume's slices) or into contiguous
// blocks (slabs of a volume), run on all cores.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

namespace at {

// Calls rowBody(row) once for every row in [0, rows), the rows handed out one at a time to up to
// hardware_concurrency threads (and at most maxThreads, 0: no limit; the calling thread among
// them), so that costly rows and cheap rows share the cores evenly. rowBody may write only what
// belongs to its row and must not throw; whatever the caller then gathers row by row, in row order,
// is the same as one thread would have made. Returns when every row is done.
template <class RowBody>
void forEachRowInParallel(int rows, const RowBody& rowBody, int maxThreads = 0) {
  const int hardware = std::max(1, int(std::thread::hardware_concurrency()));
  const int threads = std::clamp(maxThreads > 0 ? std::min(maxThreads, hardware) : hardware, 1, std::max(1, rows));
  std::atomic<int> next{0};
  const auto work = [&] {
    for (int row = next++; row < rows; row = next++) rowBody(row);
  };
  std::vector<std::jthread> helpers;
  helpers.reserve(std::size_t(threads - 1));
  for (int t = 1; t < threads; ++t) helpers.emplace_back(work);
  work();
}

// Calls blockBody(begin, end) on [0, n) cut into one contiguous block per thread — up to
// maxThreads threads (0: hardware_concurrency), never more than n — the calling thread taking the
// first block. For items that cost alike and whose neighbours share caches (the slabs of a volume,
// the lines of a separable filter). blockBody may write only what belongs to its block and must not
// throw; returns when every block is done.
template <class BlockBody>
void forEachBlockInParallel(int n, const BlockBody& blockBody, int maxThreads = 0) {
  if (n <= 0) return;
  const int hardware = std::max(1, int(std::thread::hardware_concurrency()));
  const int threads = std::clamp(maxThreads > 0 ? std::min(maxThreads, hardware) : hardware, 1, n);
  std::vector<std::jthread> helpers;
  helpers.reserve(std::size_t(threads - 1));
  for (int t = 1; t < threads; ++t)
    helpers.emplace_back([&blockBody, n, t, threads] { blockBody(int(std::int64_t(n) * t / threads), int(std::int64_t(n) * (t + 1) / threads)); });
  blockBody(0, int(std::int64_t(n) / threads));
}

}  // namespace at
