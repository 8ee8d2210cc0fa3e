// Phantom generation time. Prints one JSON line per size:
//   {"bench":"phantom","size":256,"voxels":16777216,"threads":2,"runs":5,"best_s":…,"median_s":…,"checksum":…}
// (the checksum keeps the work from being optimised away and differs between sizes)
// usage: phantom_bench [SIZE…] [--runs N]      (default sizes 128 256 512, 5 runs each)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "volume/phantom.h"

int main(int argc, char** argv) {
  std::vector<int> sizes;
  int runs = 5;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--runs" && a + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++a]));
    } else if (const int n = std::atoi(arg.c_str()); n >= 16 && n <= 1024) {
      sizes.push_back(n);
    } else {
      std::fprintf(stderr, "phantom_bench: '%s' is not a size from 16 to 1024 or --runs N\n", arg.c_str());
      return 2;
    }
  }
  if (sizes.empty()) sizes = {128, 256, 512};
  for (int size : sizes) {
    std::vector<double> seconds;
    std::size_t checksum = 0;
    for (int r = 0; r < runs; ++r) {
      at::PhantomOptions options;
      options.size = size;
      const auto t0 = std::chrono::steady_clock::now();
      const at::Dataset ds = at::makePhantom(options);
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      checksum += ds.labels.voxels[ds.labels.voxels.size() / 2] + std::size_t(ds.volume.voxels.back() + 1024);
    }
    std::sort(seconds.begin(), seconds.end());
    std::printf("{\"bench\":\"phantom\",\"size\":%d,\"voxels\":%zu,\"threads\":%u,\"runs\":%d,\"best_s\":%.4f,"
                "\"median_s\":%.4f,\"checksum\":%zu}\n",
                size, std::size_t(size) * size * size, std::thread::hardware_concurrency(), runs, seconds.front(),
                seconds[seconds.size() / 2], checksum);
  }
  return 0;
}
