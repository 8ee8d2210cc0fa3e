#include "volume/intensity_landmarks.h"

#include <algorithm>
#include <cmath>

namespace at {

namespace {
constexpr std::size_t kBins = 65536;
constexpr int kOffset = 32768;
}  // namespace

std::vector<std::uint64_t> valueHistogram(const std::vector<std::int16_t>& voxels) {
  std::vector<std::uint64_t> histogram(kBins, 0);
  for (std::int16_t v : voxels) ++histogram[std::size_t(int(v) + kOffset)];
  return histogram;
}

SoftTissueLandmarks softTissueLandmarks(const std::vector<std::uint64_t>& histogram, int air) {
  SoftTissueLandmarks out;
  air = std::clamp(air, -kOffset, kOffset - 1);
  const std::size_t size = std::min(histogram.size(), kBins);
  double count = 0, sum = 0;
  for (std::size_t v = std::size_t(air + kOffset); v < size; ++v)
    count += double(histogram[v]), sum += double(histogram[v]) * (double(v) - double(kOffset));
  out.bodyThreshold = count > 0 ? int(std::lround(0.5 * (air + sum / count))) : air;
  const auto smoothed = [&](std::size_t v) {
    std::uint64_t total = 0;
    for (std::size_t u = v >= 2 ? v - 2 : 0; u <= v + 2 && u < size; ++u) total += histogram[u];
    return total;
  };
  std::size_t valley = std::size_t(out.bodyThreshold + kOffset);
  while (valley + 1 < size && smoothed(valley + 1) <= smoothed(valley) && smoothed(valley) > 0) ++valley;
  std::size_t soft = valley;
  for (std::size_t v = soft; v < size; ++v)
    if (histogram[v] > histogram[soft]) soft = v;
  out.valley = int(valley) - kOffset;
  out.softTissue = int(soft) - kOffset;
  return out;
}

}  // namespace at
