#include "render/camera.h"

#include <cmath>

namespace at::render {

namespace {
constexpr double kPi = 3.14159265358979323846;
Vec3 normalised(const Vec3& v) {
  const double n = norm(v);
  return n > 0 ? (1.0 / n) * v : v;
}
// Rotates v about the unit axis by `rad` (Rodrigues).
Vec3 rotate(const Vec3& v, const Vec3& axis, double rad) {
  const double c = std::cos(rad), s = std::sin(rad);
  return c * v + s * cross(axis, v) + ((1 - c) * dot(axis, v)) * axis;
}
}  // namespace

Mat4 Mat4::operator*(const Mat4& o) const {
  Mat4 r;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      double s = 0;
      for (int k = 0; k < 4; ++k) s += (*this)(i, k) * o(k, j);
      r(i, j) = s;
    }
  return r;
}

Vec3 Mat4::transformPoint(const Vec3& p) const {
  double v[4];
  for (int r = 0; r < 4; ++r) v[r] = (*this)(r, 0) * p[0] + (*this)(r, 1) * p[1] + (*this)(r, 2) * p[2] + (*this)(r, 3);
  return {v[0] / v[3], v[1] / v[3], v[2] / v[3]};
}

Vec3 Mat4::transformDirection(const Vec3& d) const {
  Vec3 v;
  for (int r = 0; r < 3; ++r) v[r] = (*this)(r, 0) * d[0] + (*this)(r, 1) * d[1] + (*this)(r, 2) * d[2];
  return v;
}

Mat4 Mat4::inverse() const {
  // Gauss–Jordan with partial pivoting.
  double a[4][8];
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      a[r][c] = (*this)(r, c);
      a[r][c + 4] = r == c ? 1 : 0;
    }
  for (int c = 0; c < 4; ++c) {
    int pivot = c;
    for (int r = c + 1; r < 4; ++r)
      if (std::fabs(a[r][c]) > std::fabs(a[pivot][c])) pivot = r;
    for (int k = 0; k < 8; ++k) std::swap(a[c][k], a[pivot][k]);
    const double inv = 1.0 / a[c][c];
    for (int k = 0; k < 8; ++k) a[c][k] *= inv;
    for (int r = 0; r < 4; ++r) {
      if (r == c) continue;
      const double f = a[r][c];
      for (int k = 0; k < 8; ++k) a[r][k] -= f * a[c][k];
    }
  }
  Mat4 out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out(r, c) = a[r][c + 4];
  return out;
}

std::array<float, 16> Mat4::toFloat() const {
  std::array<float, 16> f;
  for (std::size_t i = 0; i < 16; ++i) f[i] = float(m[i]);
  return f;
}

std::optional<NamedView> parseNamedView(const std::string& name) {
  for (NamedView v : {NamedView::Anterior, NamedView::Posterior, NamedView::LateralLeft, NamedView::LateralRight,
                      NamedView::Superior, NamedView::Inferior})
    if (name == toString(v)) return v;
  return std::nullopt;
}

const char* toString(NamedView view) {
  switch (view) {
    case NamedView::Anterior: return "anterior";
    case NamedView::Posterior: return "posterior";
    case NamedView::LateralLeft: return "lateral_left";
    case NamedView::LateralRight: return "lateral_right";
    case NamedView::Superior: return "superior";
    case NamedView::Inferior: return "inferior";
  }
  return "anterior";
}

Camera::Camera() = default;

Camera Camera::named(NamedView view, const Vec3& target, double radiusMm) {
  Camera c;
  c.target = target;
  c.distanceMm = radiusMm / std::sin(c.fovYDeg * kPi / 360.0);
  // Direction from the eye to the target, and the screen's up, in LPS.
  switch (view) {
    case NamedView::Anterior: c.forward_ = {0, 1, 0}; c.up_ = {0, 0, 1}; break;
    case NamedView::Posterior: c.forward_ = {0, -1, 0}; c.up_ = {0, 0, 1}; break;
    case NamedView::LateralLeft: c.forward_ = {-1, 0, 0}; c.up_ = {0, 0, 1}; break;
    case NamedView::LateralRight: c.forward_ = {1, 0, 0}; c.up_ = {0, 0, 1}; break;
    case NamedView::Superior: c.forward_ = {0, 0, -1}; c.up_ = {0, -1, 0}; break;
    case NamedView::Inferior: c.forward_ = {0, 0, 1}; c.up_ = {0, -1, 0}; break;
  }
  return c;
}

Result<Camera> Camera::named(const std::string& view, const Vec3& target, double radiusMm) {
  const auto v = parseNamedView(view);
  if (!v)
    return fail("unknown view '" + view +
                "' (expected anterior, posterior, lateral_left, lateral_right, superior or inferior)");
  return named(*v, target, radiusMm);
}

Result<Camera> Camera::looking(const Vec3& target, const Vec3& forward, const Vec3& up, double distanceMm) {
  if (!(distanceMm > 0) || !std::isfinite(distanceMm)) return fail("a camera's distance must be above 0 mm");
  const double f = std::sqrt(dot(forward, forward));
  if (!(f > 1e-9) || !std::isfinite(f)) return fail("a camera's viewing direction must not be zero");
  Camera c;
  c.target = target;
  c.distanceMm = distanceMm;
  c.forward_ = (1.0 / f) * forward;
  const Vec3 across = up - dot(up, c.forward_) * c.forward_;
  const double u = std::sqrt(dot(across, across));
  if (!(u > 1e-6) || !std::isfinite(u)) return fail("a camera's up direction must not be zero or along its viewing direction");
  c.up_ = (1.0 / u) * across;
  return c;
}

Vec3 Camera::eye() const { return target - distanceMm * forward_; }

void Camera::orbit(double azimuthDeg, double elevationDeg) {
  const Vec3 right = normalised(cross(forward_, up_));
  forward_ = normalised(rotate(forward_, up_, azimuthDeg * kPi / 180.0));
  const Vec3 right2 = normalised(rotate(right, up_, azimuthDeg * kPi / 180.0));
  forward_ = normalised(rotate(forward_, right2, elevationDeg * kPi / 180.0));
  up_ = normalised(rotate(up_, right2, elevationDeg * kPi / 180.0));
}

void Camera::zoom(double factor) {
  if (factor > 0) distanceMm /= factor;
}

double Camera::nearMm() const { return distanceMm * 0.02; }
double Camera::farMm() const { return distanceMm * 5; }

Mat4 Camera::view() const {
  const Vec3 f = forward_;
  const Vec3 s = normalised(cross(f, up_));
  const Vec3 u = cross(s, f);
  const Vec3 e = eye();
  Mat4 v;
  for (int c = 0; c < 3; ++c) {
    v(0, c) = s[std::size_t(c)];
    v(1, c) = u[std::size_t(c)];
    v(2, c) = -f[std::size_t(c)];
  }
  v(0, 3) = -dot(s, e);
  v(1, 3) = -dot(u, e);
  v(2, 3) = dot(f, e);
  return v;
}

Mat4 Camera::projection(double aspect) const {
  const double n = nearMm(), f = farMm();
  const double tanHalf = std::tan(fovYDeg * kPi / 360.0);
  Mat4 p;
  if (orthographic) {
    const double h = distanceMm * tanHalf, w = h * aspect;
    p(0, 0) = 1 / w;
    p(1, 1) = 1 / h;
    p(2, 2) = -2 / (f - n);
    p(2, 3) = -(f + n) / (f - n);
    return p;
  }
  p(0, 0) = 1 / (tanHalf * aspect);
  p(1, 1) = 1 / tanHalf;
  p(2, 2) = -(f + n) / (f - n);
  p(2, 3) = -2 * f * n / (f - n);
  p(3, 2) = -1;
  p(3, 3) = 0;
  return p;
}

Ray Camera::rayThroughPixel(double x, double y, int width, int height) const {
  const Mat4 inv = viewProjection(double(width) / double(height)).inverse();
  const double ndcX = 2 * (x + 0.5) / width - 1, ndcY = 1 - 2 * (y + 0.5) / height;
  const Vec3 a = inv.transformPoint({ndcX, ndcY, -1});
  const Vec3 b = inv.transformPoint({ndcX, ndcY, 1});
  return {a, normalised(b - a)};
}

std::optional<std::array<double, 2>> Camera::project(const Vec3& p, int width, int height) const {
  if (dot(p - eye(), forward_) <= 0) return std::nullopt;
  const Vec3 ndc = viewProjection(double(width) / double(height)).transformPoint(p);
  return std::array<double, 2>{(ndc[0] + 1) * 0.5 * width - 0.5, (1 - ndc[1]) * 0.5 * height - 0.5};
}

Result<ClipPlane> ClipPlane::fromCoefficients(double nx, double ny, double nz, double d) {
  const double n = std::sqrt(nx * nx + ny * ny + nz * nz);
  if (!(n > 0) || !std::isfinite(n)) return fail("clip plane needs a non-zero normal (got " + std::to_string(nx) + "," +
                                                 std::to_string(ny) + "," + std::to_string(nz) + ")");
  return ClipPlane{{nx / n, ny / n, nz / n}, d / n};
}

}  // namespace at::render
