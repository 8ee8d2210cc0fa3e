#include "volume/label_fit.h"

#include <cmath>
#include <cstdio>
#include <vector>

namespace at {

LabelFit measureLabelFit(const Volume& volume, const LabelMap& labels, double bodyStored) {
  LabelFit fit;
  const Dims d = volume.dims();
  if (labels.dims() != d) return fit;
  // Per k-slice: for each row (fixed j) the first and last body voxel along i, and for each column
  // (fixed i) the first and last along j. Enclosed = between both pairs.
  std::vector<int> rowLo(std::size_t(d.y)), rowHi(std::size_t(d.y)), colLo(std::size_t(d.x)), colHi(std::size_t(d.x));
  for (int k = 0; k < d.z; ++k) {
    std::fill(rowLo.begin(), rowLo.end(), d.x);
    std::fill(rowHi.begin(), rowHi.end(), -1);
    std::fill(colLo.begin(), colLo.end(), d.y);
    std::fill(colHi.begin(), colHi.end(), -1);
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (volume.at(i, j, k) >= bodyStored) {
          rowLo[std::size_t(j)] = std::min(rowLo[std::size_t(j)], i);
          rowHi[std::size_t(j)] = std::max(rowHi[std::size_t(j)], i);
          colLo[std::size_t(i)] = std::min(colLo[std::size_t(i)], j);
          colHi[std::size_t(i)] = std::max(colHi[std::size_t(i)], j);
        }
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        if (labels.at(i, j, k) == 0) continue;
        ++fit.labelled;
        const bool inside = i >= rowLo[std::size_t(j)] && i <= rowHi[std::size_t(j)] && j >= colLo[std::size_t(i)] &&
                            j <= colHi[std::size_t(i)];
        fit.outsideBody += !inside;
      }
  }
  return fit;
}

std::string labelFitWarning(const Volume& volume, const IntensityModel& intensity, const LabelMap& labels,
                            const std::string& labelsPath, double maxOutside) {
  if (!intensity.hounsfield() || !(intensity.slope > 0)) return {};
  const double airHu = -500;
  const LabelFit fit = measureLabelFit(volume, labels, (airHu - intensity.intercept) / intensity.slope);
  if (fit.labelled < 1000 || fit.outsideFraction() <= maxOutside) return {};
  char text[160];
  std::snprintf(text, sizeof text, "%.0f %% of its %zu labelled voxels lie on air outside the body",
                100 * fit.outsideFraction(), fit.labelled);
  return labelsPath + ": " + text +
         " - the label map does not fit this volume (check its header: origin, slice order or orientation)";
}

}  // namespace at
