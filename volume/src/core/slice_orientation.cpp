#include "volume/slice_orientation.h"

#include <cmath>

namespace at {
namespace {

// The letter of patient axis `p` (0 x, 1 y, 2 z in LPS) in direction `sign`.
char letter(int p, int sign) {
  static const char pos[3] = {'L', 'P', 'S'}, neg[3] = {'R', 'A', 'I'};
  return sign >= 0 ? pos[p] : neg[p];
}

// The patient direction (axis, sign) that voxel axis `v` walked forwards (or reversed) points to most.
char letterOfVoxelAxis(const Mat3& direction, int v, bool reversed) {
  const Vec3 c = direction.column(v);
  int best = 0;
  for (int p = 1; p < 3; ++p)
    if (std::abs(c[std::size_t(p)]) > std::abs(c[std::size_t(best)])) best = p;
  const int sign = (c[std::size_t(best)] >= 0) != reversed ? 1 : -1;
  return letter(best, sign);
}

void setLetters(SliceLayout& l, const Mat3& direction) {
  l.right = letterOfVoxelAxis(direction, l.columnAxis, l.columnReversed);
  l.left = letterOfVoxelAxis(direction, l.columnAxis, !l.columnReversed);
  l.bottom = letterOfVoxelAxis(direction, l.rowAxis, l.rowReversed);
  l.top = letterOfVoxelAxis(direction, l.rowAxis, !l.rowReversed);
}

}  // namespace

const char* planeName(PatientPlane plane) {
  switch (plane) {
    case PatientPlane::Sagittal: return "sagittal";
    case PatientPlane::Coronal: return "coronal";
    case PatientPlane::Axial: return "axial";
  }
  return "?";
}

std::string SliceLayout::edgeLetters() const {
  return std::string("left ") + left + ", right " + right + ", top " + top + ", bottom " + bottom;
}

SliceLayout patientSliceLayout(const Mat3& direction, PatientPlane plane) {
  // voxelOf[p]: the voxel axis matched to patient axis p (LPS x, y, z), the permutation with the
  // largest total |cosine|.
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  int best = 0;
  double bestScore = -1;
  for (int n = 0; n < 6; ++n) {
    double score = 0;
    for (int p = 0; p < 3; ++p) score += std::abs(direction.m[std::size_t(p)][std::size_t(perms[n][p])]);
    if (score > bestScore + 1e-12) bestScore = score, best = n;
  }
  const int* voxelOf = perms[best];
  // Screen right and screen down as (patient axis, sign) in LPS, and the axis across the pane.
  int normal = 2, rightAxis = 0, rightSign = 1, downAxis = 1, downSign = 1;  // axial: right L, down P
  if (plane == PatientPlane::Coronal) normal = 1, rightAxis = 0, rightSign = 1, downAxis = 2, downSign = -1;
  if (plane == PatientPlane::Sagittal) normal = 0, rightAxis = 1, rightSign = 1, downAxis = 2, downSign = -1;
  SliceLayout l;
  l.sliceAxis = voxelOf[normal];
  l.columnAxis = voxelOf[rightAxis];
  l.rowAxis = voxelOf[downAxis];
  const auto cosine = [&](int p) { return direction.m[std::size_t(p)][std::size_t(voxelOf[p])]; };
  l.columnReversed = (cosine(rightAxis) >= 0) != (rightSign > 0);
  l.rowReversed = (cosine(downAxis) >= 0) != (downSign > 0);
  setLetters(l, direction);
  return l;
}

SliceLayout voxelSliceLayout(int axis, const Mat3& direction) {
  SliceLayout l;
  l.sliceAxis = axis;
  l.columnAxis = axis == 0 ? 1 : 0;
  l.rowAxis = axis == 2 ? 1 : 2;
  l.columnReversed = false;
  l.rowReversed = l.rowAxis == 2;
  setLetters(l, direction);
  return l;
}

}  // namespace at
