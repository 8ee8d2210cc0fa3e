// Helpers for the loader tests: byte-level file access, hand-made NIfTI headers (so that tests
// control every field, including broken ones), and random oblique geometries.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include <doctest/doctest.h>

#include "volume/geometry.h"
#include "volume/image_file.h"

namespace at::test {

inline std::string readBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline void writeBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
}

template <class T>
void putValue(std::string& buffer, std::size_t offset, T value) {
  std::memcpy(buffer.data() + offset, &value, sizeof(T));
}

// Fields of a single-file NIfTI header written by hand. Affines are in NIfTI's RAS+ world.
struct RawNifti {
  int version = 1;                // 1 or 2
  int dims[3] = {2, 2, 2};
  int extraDim4 = 1;              // dim[4] (time points)
  std::int16_t datatype = 4;      // DT_INT16
  std::int16_t bitpix = 16;
  double pixdim[3] = {1, 1, 1};
  double slope = 0, inter = 0;
  int qformCode = 0, sformCode = 0;
  double quatern[3] = {0, 0, 0};  // b, c, d
  double qoffset[3] = {0, 0, 0};
  double qfac = 1;
  double srow[3][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}};
  std::string data;               // voxel bytes, little endian

  std::string bytes() const {
    std::string b;
    if (version == 1) {
      b.assign(352, '\0');
      putValue<std::int32_t>(b, 0, 348);
      putValue<std::int16_t>(b, 40, extraDim4 > 1 ? 4 : 3);
      for (int a = 0; a < 3; ++a) putValue<std::int16_t>(b, 42 + 2 * std::size_t(a), std::int16_t(dims[a]));
      putValue<std::int16_t>(b, 48, std::int16_t(extraDim4));
      for (int a = 4; a < 7; ++a) putValue<std::int16_t>(b, 42 + 2 * std::size_t(a), 1);
      putValue<std::int16_t>(b, 70, datatype);
      putValue<std::int16_t>(b, 72, bitpix);
      putValue<float>(b, 76, float(qfac));
      for (int a = 0; a < 3; ++a) putValue<float>(b, 80 + 4 * std::size_t(a), float(pixdim[a]));
      putValue<float>(b, 108, 352.0f);
      putValue<float>(b, 112, float(slope));
      putValue<float>(b, 116, float(inter));
      b[123] = 2;  // mm
      putValue<std::int16_t>(b, 252, std::int16_t(qformCode));
      putValue<std::int16_t>(b, 254, std::int16_t(sformCode));
      for (int a = 0; a < 3; ++a) putValue<float>(b, 256 + 4 * std::size_t(a), float(quatern[a]));
      for (int a = 0; a < 3; ++a) putValue<float>(b, 268 + 4 * std::size_t(a), float(qoffset[a]));
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) putValue<float>(b, 280 + 16 * std::size_t(r) + 4 * std::size_t(c), float(srow[r][c]));
      std::memcpy(b.data() + 344, "n+1\0", 4);
    } else {
      b.assign(544, '\0');
      putValue<std::int32_t>(b, 0, 540);
      std::memcpy(b.data() + 4, "n+2\0\r\n\032\n", 8);
      putValue<std::int16_t>(b, 12, datatype);
      putValue<std::int16_t>(b, 14, bitpix);
      putValue<std::int64_t>(b, 16, extraDim4 > 1 ? 4 : 3);
      for (int a = 0; a < 3; ++a) putValue<std::int64_t>(b, 24 + 8 * std::size_t(a), dims[a]);
      putValue<std::int64_t>(b, 48, extraDim4);
      for (int a = 4; a < 7; ++a) putValue<std::int64_t>(b, 24 + 8 * std::size_t(a), 1);
      putValue<double>(b, 104, qfac);
      for (int a = 0; a < 3; ++a) putValue<double>(b, 112 + 8 * std::size_t(a), pixdim[a]);
      putValue<std::int64_t>(b, 168, 544);
      putValue<double>(b, 176, slope);
      putValue<double>(b, 184, inter);
      putValue<std::int32_t>(b, 344, qformCode);
      putValue<std::int32_t>(b, 348, sformCode);
      for (int a = 0; a < 3; ++a) putValue<double>(b, 352 + 8 * std::size_t(a), quatern[a]);
      for (int a = 0; a < 3; ++a) putValue<double>(b, 376 + 8 * std::size_t(a), qoffset[a]);
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 4; ++c) putValue<double>(b, 400 + 32 * std::size_t(r) + 8 * std::size_t(c), srow[r][c]);
      putValue<std::int32_t>(b, 500, 2);
    }
    return b + data;
  }
};

// A random rotation (from a random unit quaternion), spacing 0.3..3 mm and origin within ±200 mm.
// A loader's error for a broken input: one line that starts with the file's path and says `expected`.
template <class T>
void checkError(const Result<T>& result, const std::string& path, const std::string& expected) {
  REQUIRE_FALSE(result.has_value());
  const std::string& message = result.error().message;
  CAPTURE(message);
  CHECK(message.rfind(path, 0) == 0);
  CHECK(message.find(expected) != std::string::npos);
  CHECK(message.find('\n') == std::string::npos);
}

inline Geometry randomObliqueGeometry(std::mt19937_64& rng, Dims dims) {
  std::normal_distribution<double> normal;
  double q[4];
  double length = 0;
  do {
    length = 0;
    for (double& v : q) {
      v = normal(rng);
      length += v * v;
    }
  } while (length < 1e-6);
  length = std::sqrt(length);
  for (double& v : q) v /= length;
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  Geometry g;
  g.dims = dims;
  g.direction.m = {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                    {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                    {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};
  std::uniform_real_distribution<double> spacing(0.3, 3.0), origin(-200, 200);
  for (int a = 0; a < 3; ++a) {
    g.spacingMm[std::size_t(a)] = spacing(rng);
    g.originMm[std::size_t(a)] = origin(rng);
  }
  return g;
}

inline double maxAbsDifference(const Mat3& a, const Mat3& b) {
  double d = 0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(a.m[std::size_t(r)][std::size_t(c)] - b.m[std::size_t(r)][std::size_t(c)]));
  return d;
}

inline double maxAbsDifference(const Vec3& a, const Vec3& b) {
  return std::max({std::abs(a[0] - b[0]), std::abs(a[1] - b[1]), std::abs(a[2] - b[2])});
}

}  // namespace at::test
