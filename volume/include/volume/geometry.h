// Voxel grids in the patient frame. Index (i, j, k) maps to a point in millimetres in LPS
// (x → patient Left, y → Posterior, z → Superior) by
//   p = origin + direction · diag(spacing) · (i, j, k)
// where the columns of `direction` are the unit vectors of the i, j and k axes in LPS.
// i is the contiguous axis in memory: index = i + dims.x * (j + dims.y * k).
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

namespace at {

using Vec3 = std::array<double, 3>;

// Row-major 3×3 matrix: m[row][col].
struct Mat3 {
  std::array<std::array<double, 3>, 3> m{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};

  static Mat3 identity() { return {}; }
  Vec3 column(int c) const { return {m[0][c], m[1][c], m[2][c]}; }
  Vec3 operator*(const Vec3& v) const {
    return {m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
            m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
            m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]};
  }
  Mat3 operator*(const Mat3& o) const;
  double determinant() const;
  // Inverse; the caller guarantees a non-singular matrix (direction cosines always are).
  Mat3 inverse() const;
};

inline Vec3 operator+(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 operator-(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 operator*(double s, const Vec3& a) { return {s * a[0], s * a[1], s * a[2]}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }

struct Dims {
  int x = 0, y = 0, z = 0;

  std::size_t count() const { return std::size_t(x) * std::size_t(y) * std::size_t(z); }
  bool contains(int i, int j, int k) const { return i >= 0 && j >= 0 && k >= 0 && i < x && j < y && k < z; }
  std::size_t index(int i, int j, int k) const {
    return std::size_t(i) + std::size_t(x) * (std::size_t(j) + std::size_t(y) * std::size_t(k));
  }
  bool operator==(const Dims&) const = default;
  std::string toString() const;  // "512x512x20"
};

struct Geometry {
  Dims dims;
  Vec3 spacingMm{1, 1, 1};
  Vec3 originMm{0, 0, 0};        // centre of voxel (0,0,0) in LPS
  Mat3 direction = Mat3::identity();  // columns: unit i, j, k axes in LPS

  Vec3 indexToPatient(const Vec3& ijk) const;
  Vec3 patientToIndex(const Vec3& lps) const;
  // Centre of the grid's bounding box in LPS millimetres.
  Vec3 centreMm() const;
  // Physical size of the grid along i, j, k in millimetres (dims × spacing).
  Vec3 extentMm() const;
  // Same dims and, within `toleranceMm`, the same voxel positions.
  bool sameGridAs(const Geometry& other, double toleranceMm = 1e-3) const;
  // "up to 3 letters" orientation code of the i, j, k axes in LPS terms, e.g. "LPS", "RAS", "LPI".
  std::string orientationCode() const;
};

// Millimetre floors written for CT and a 0.1 mm µCT (the least half-height of a view, a distance
// unit's floor, a brush's default radius) are scaled by this below kFineVoxelMm, so a finer µCT
// gets them voxel for voxel as at 0.1 mm: 1 for `voxelMm` ≥ kFineVoxelMm (and for 0, unknown),
// voxelMm / kFineVoxelMm below.
constexpr double kFineVoxelMm = 0.1;
inline double fineVoxelScale(double voxelMm) { return voxelMm > 0 && voxelMm < kFineVoxelMm ? voxelMm / kFineVoxelMm : 1.0; }

}  // namespace at
