// Camera for the volume view: orbits a target in the patient frame (LPS millimetres), zooms by
// changing its distance, and gives the GL-convention view and projection matrices (column-major,
// right-handed eye space looking down −z). Also the named views and the clipping plane.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "core/error.h"
#include "volume/geometry.h"

namespace at::render {

// 4×4 matrix, column-major as GL expects: m[col * 4 + row].
struct Mat4 {
  std::array<double, 16> m{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  double& operator()(int row, int col) { return m[std::size_t(col * 4 + row)]; }
  double operator()(int row, int col) const { return m[std::size_t(col * 4 + row)]; }
  Mat4 operator*(const Mat4& o) const;
  // Transforms the point (x, y, z, 1) and divides by w.
  Vec3 transformPoint(const Vec3& p) const;
  Vec3 transformDirection(const Vec3& d) const;  // w = 0, no division
  Mat4 inverse() const;  // the caller guarantees a non-singular matrix
  std::array<float, 16> toFloat() const;
};

// Views named from the patient's side the camera looks from, in LPS: anterior = camera in front of
// the patient (−y) looking back; lateral_left = camera on the patient's left (+x).
enum class NamedView { Anterior, Posterior, LateralLeft, LateralRight, Superior, Inferior };
std::optional<NamedView> parseNamedView(const std::string& name);
const char* toString(NamedView view);

struct Ray {
  Vec3 origin;     // mm, LPS
  Vec3 direction;  // unit
};

class Camera {
 public:
  Vec3 target{0, 0, 0};
  double distanceMm = 100;
  double fovYDeg = 30;          // perspective field of view
  bool orthographic = false;    // then the view height is 2·distanceMm·tan(fovY/2) at any depth

  Camera();
  // A camera looking at `target` from the named side, far enough that a sphere of `radiusMm`
  // around the target fills the view.
  static Camera named(NamedView view, const Vec3& target, double radiusMm);
  static Result<Camera> named(const std::string& view, const Vec3& target, double radiusMm);
  // A camera `distanceMm` (> 0) from `target` looking along `forward` with `up` the screen's up
  // (both normalised here, `up` made orthogonal to `forward`). Error for a zero `forward` or an
  // `up` along it.
  static Result<Camera> looking(const Vec3& target, const Vec3& forward, const Vec3& up, double distanceMm);

  Vec3 eye() const;
  const Vec3& forward() const { return forward_; }  // unit, from eye towards target
  const Vec3& up() const { return up_; }            // unit, orthogonal to forward
  // Rotates the eye about the target: azimuth about `up`, elevation about the right axis.
  void orbit(double azimuthDeg, double elevationDeg);
  // factor > 1 moves closer (the distance is divided by it).
  void zoom(double factor);

  Mat4 view() const;
  Mat4 projection(double aspect) const;  // aspect = width / height
  Mat4 viewProjection(double aspect) const { return projection(aspect) * view(); }
  // The ray through the centre of pixel (x, y) of a width × height image; y = 0 is the top row.
  Ray rayThroughPixel(double x, double y, int width, int height) const;
  // Pixel coordinates (x right, y down, pixel centres at +0.5) of a point; nullopt behind the eye.
  std::optional<std::array<double, 2>> project(const Vec3& p, int width, int height) const;

  double nearMm() const;
  double farMm() const;

  bool operator==(const Camera&) const = default;

 private:
  Vec3 forward_{0, 1, 0};
  Vec3 up_{0, 0, 1};
};

// Samples with dot(normal, p) > d (p in LPS mm) are cut away: the plane removes the side its
// normal points to.
struct ClipPlane {
  Vec3 normal{1, 0, 0};  // unit
  double d = 0;
  bool keeps(const Vec3& p) const { return dot(normal, p) <= d; }
  bool operator==(const ClipPlane&) const = default;
  // Normalises (nx, ny, nz) and scales d with it. Error for a zero normal.
  static Result<ClipPlane> fromCoefficients(double nx, double ny, double nz, double d);
};

}  // namespace at::render
