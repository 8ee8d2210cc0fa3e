#include "wdt/answer_keys.h"

#include <cmath>

#include "field_sampling.h"

namespace at::wdt {

WdtParams answerKeyParams() {
  WdtParams params;
  params.converge = true;
  params.downsample = 2;
  return params;
}

Result<FloatVolume> answerKeyDistances(const Volume& volume, const Geometry& labelGrid, const Mask& seeds) {
  auto result = computeWdt(volume, seeds, answerKeyParams());
  if (!result) return tl::unexpected(result.error());
  if (result->field.downsample == 1) return std::move(result->field.distances);
  return upsampleField(result->field, labelGrid);
}

std::optional<double> answerKeyDistanceAt(const DistanceField& field, const Geometry& labelGrid, const Vec3& pointMm) {
  const Vec3 ijk = labelGrid.patientToIndex(pointMm);
  const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
  if (!labelGrid.dims.contains(i, j, k) || field.distances.geometry.dims.count() == 0) return std::nullopt;
  // A field on the label grid itself (downsample 1 on a volume whose grid the labels share) is read as is.
  const double d = field.downsample == 1 && field.distances.geometry.dims == labelGrid.dims
                       ? double(field.distances.at(i, j, k))
                       : double(detail::sampleMapped(field.distances, detail::GridMap(field.distances.geometry, labelGrid), i, j, k));
  if (!std::isfinite(d)) return std::nullopt;
  return d;
}

}  // namespace at::wdt
