#include "volume/geometry.h"

#include <cstdio>

namespace at {

Mat3 Mat3::operator*(const Mat3& o) const {
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += m[i][k] * o.m[k][j];
      r.m[i][j] = s;
    }
  return r;
}

double Mat3::determinant() const {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
         m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

Mat3 Mat3::inverse() const {
  const double d = determinant();
  Mat3 r;
  r.m[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / d;
  r.m[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / d;
  r.m[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / d;
  r.m[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / d;
  r.m[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / d;
  r.m[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / d;
  r.m[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / d;
  r.m[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / d;
  r.m[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / d;
  return r;
}

std::string Dims::toString() const {
  return std::to_string(x) + "x" + std::to_string(y) + "x" + std::to_string(z);
}

Vec3 Geometry::indexToPatient(const Vec3& ijk) const {
  const Vec3 scaled{ijk[0] * spacingMm[0], ijk[1] * spacingMm[1], ijk[2] * spacingMm[2]};
  return originMm + direction * scaled;
}

Vec3 Geometry::patientToIndex(const Vec3& lps) const {
  const Vec3 local = direction.inverse() * (lps - originMm);
  return {local[0] / spacingMm[0], local[1] / spacingMm[1], local[2] / spacingMm[2]};
}

Vec3 Geometry::centreMm() const {
  return indexToPatient({(dims.x - 1) * 0.5, (dims.y - 1) * 0.5, (dims.z - 1) * 0.5});
}

Vec3 Geometry::extentMm() const {
  return {dims.x * spacingMm[0], dims.y * spacingMm[1], dims.z * spacingMm[2]};
}

bool Geometry::sameGridAs(const Geometry& other, double toleranceMm) const {
  if (!(dims == other.dims)) return false;
  const Vec3 corners[2] = {{0, 0, 0}, {double(dims.x - 1), double(dims.y - 1), double(dims.z - 1)}};
  for (const Vec3& c : corners)
    if (norm(indexToPatient(c) - other.indexToPatient(c)) > toleranceMm) return false;
  for (int axis = 0; axis < 3; ++axis) {
    Vec3 unit{0, 0, 0};
    unit[axis] = 1;
    if (norm(indexToPatient(unit) - other.indexToPatient(unit)) > toleranceMm) return false;
  }
  return true;
}

std::string Geometry::orientationCode() const {
  // Each axis is named by the LPS direction it points to most: +x L / -x R, +y P / -y A, +z S / -z I.
  std::string code;
  for (int c = 0; c < 3; ++c) {
    const Vec3 v = direction.column(c);
    int best = 0;
    for (int r = 1; r < 3; ++r)
      if (std::abs(v[r]) > std::abs(v[best])) best = r;
    static const char pos[3] = {'L', 'P', 'S'};
    static const char neg[3] = {'R', 'A', 'I'};
    code += v[best] >= 0 ? pos[best] : neg[best];
  }
  return code;
}

}  // namespace at
