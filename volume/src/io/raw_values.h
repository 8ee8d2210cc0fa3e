// Shared by the loaders that read raw voxel bytes (NRRD, InVesalius): the size of a stored scalar
// and the conversion of a byte buffer to float values.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "volume/image_file.h"

namespace at::detail {

inline std::size_t bytesOf(ScalarKind kind) {
  switch (kind) {
    case ScalarKind::Int8:
    case ScalarKind::UInt8: return 1;
    case ScalarKind::Int16:
    case ScalarKind::UInt16: return 2;
    case ScalarKind::Int32:
    case ScalarKind::UInt32:
    case ScalarKind::Float32: return 4;
    case ScalarKind::Float64: return 8;
  }
  return 1;
}

template <class T>
void convertValues(const unsigned char* bytes, std::size_t count, bool swap, float* out) {
  for (std::size_t i = 0; i < count; ++i) {
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, bytes + i * sizeof(T), sizeof(T));
    if (swap)
      for (std::size_t b = 0; b < sizeof(T) / 2; ++b) std::swap(raw[b], raw[sizeof(T) - 1 - b]);
    T v;
    std::memcpy(&v, raw, sizeof(T));
    out[i] = float(v);
  }
}

// Writes `count` values of `kind`, stored in `bytes` (count · bytesOf(kind) of them, any
// alignment), to `out` as floats; `swap` reverses each value's bytes (big-endian data on this
// little-endian machine, or the other way round).
inline void decodeRawValues(const unsigned char* bytes, std::size_t count, ScalarKind kind, bool swap, float* out) {
  switch (kind) {
    case ScalarKind::Int8: convertValues<std::int8_t>(bytes, count, swap, out); break;
    case ScalarKind::UInt8: convertValues<std::uint8_t>(bytes, count, swap, out); break;
    case ScalarKind::Int16: convertValues<std::int16_t>(bytes, count, swap, out); break;
    case ScalarKind::UInt16: convertValues<std::uint16_t>(bytes, count, swap, out); break;
    case ScalarKind::Int32: convertValues<std::int32_t>(bytes, count, swap, out); break;
    case ScalarKind::UInt32: convertValues<std::uint32_t>(bytes, count, swap, out); break;
    case ScalarKind::Float32: convertValues<float>(bytes, count, swap, out); break;
    case ScalarKind::Float64: convertValues<double>(bytes, count, swap, out); break;
  }
}

// Fills `out` (already sized) from `bytes`, which hold out.size() values of `kind`.
inline void decodeRawValues(const std::string& bytes, ScalarKind kind, bool swap, std::vector<float>& out) {
  decodeRawValues(reinterpret_cast<const unsigned char*>(bytes.data()), out.size(), kind, swap, out.data());
}

}  // namespace at::detail
