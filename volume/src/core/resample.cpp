#include "volume/resample.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <vector>

#include "core/parallel_rows.h"

namespace at {

Result<LabelMap> resampleLabelsNearest(const LabelMap& source, const Geometry& target) {
  const Geometry& src = source.geometry;
  if (source.voxels.size() != src.dims.count() || src.dims.count() == 0) return fail("resampling: source label map is empty");
  if (target.dims.count() == 0) return fail("resampling: target grid is empty");

  // Target index → source continuous index is affine: c = A · ijk + b.
  Mat3 targetScaled = target.direction;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) targetScaled.m[r][c] *= target.spacingMm[std::size_t(c)];
  Mat3 sourceScaled = src.direction;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) sourceScaled.m[r][c] *= src.spacingMm[std::size_t(c)];
  const Mat3 sourceInverse = sourceScaled.inverse();
  const Mat3 A = sourceInverse * targetScaled;
  const Vec3 b = sourceInverse * (target.originMm - src.originMm);

  LabelMap out(target, 0);
  const Dims& td = target.dims;
  const Dims& sd = src.dims;
  std::atomic<std::size_t> inside{0};

  auto work = [&](int kBegin, int kEnd) {
    std::size_t count = 0;
    for (int k = kBegin; k < kEnd; ++k)
      for (int j = 0; j < td.y; ++j) {
        const Vec3 rowStart = A * Vec3{0.0, double(j), double(k)} + b;
        const Vec3 step = A.column(0);
        std::uint16_t* row = &out.voxels[td.index(0, j, k)];
        for (int i = 0; i < td.x; ++i) {
          const double x = rowStart[0] + step[0] * i, y = rowStart[1] + step[1] * i, z = rowStart[2] + step[2] * i;
          const double si = std::floor(x + 0.5), sj = std::floor(y + 0.5), sk = std::floor(z + 0.5);
          if (si < 0 || sj < 0 || sk < 0 || si >= sd.x || sj >= sd.y || sk >= sd.z) continue;
          ++count;
          row[i] = source.voxels[sd.index(int(si), int(sj), int(sk))];
        }
      }
    inside += count;
  };

  // A small grid on the calling thread alone (threads cost more than its work).
  forEachBlockInParallel(td.z, work, td.count() < 65536 ? 1 : 0);
  if (inside.load() == 0)
    return fail("resampling: the label grid (" + sd.toString() + ", centre " + std::to_string(src.centreMm()[0]) +
                "," + std::to_string(src.centreMm()[1]) + "," + std::to_string(src.centreMm()[2]) +
                " mm LPS) does not overlap the target grid (" + td.toString() + ", centre " +
                std::to_string(target.centreMm()[0]) + "," + std::to_string(target.centreMm()[1]) + "," +
                std::to_string(target.centreMm()[2]) + " mm LPS)");
  return out;
}

std::vector<LostLabel> labelsLostInResampling(const LabelMap& source, const LabelMap& resampled) {
  std::vector<std::size_t> before(65536, 0);
  std::vector<bool> after(65536, false);
  for (std::uint16_t v : source.voxels) ++before[v];
  for (std::uint16_t v : resampled.voxels) after[v] = true;
  std::vector<LostLabel> lost;
  for (std::size_t label = 1; label < before.size(); ++label)
    if (before[label] && !after[label]) lost.push_back({std::uint16_t(label), before[label]});
  return lost;
}

}  // namespace at
