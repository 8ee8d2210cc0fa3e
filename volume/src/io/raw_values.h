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
void convertValues(const std::string& bytes, bool swap, std::vector<float>& out) {
  const std::size_t n = out.size();
  for (std::size_t i = 0; i < n; ++i) {
    unsigned char raw[sizeof(T)];
    std::memcpy(raw, bytes.data() + i * sizeof(T), sizeof(T));
    if (swap)
      for (std::size_t b = 0; b < sizeof(T) / 2; ++b) std::swap(raw[b], raw[sizeof(T) - 1 - b]);
    T v;
    std::memcpy(&v, raw, sizeof(T));
    out[i] = float(v);
  }
}

// Fills `out` (already sized) from `bytes`, which hold out.size() values of `kind`; `swap` reverses
// each value's bytes (big-endian data on this little-endian machine, or the other way round).
inline void decodeRawValues(const std::string& bytes, ScalarKind kind, bool swap, std::vector<float>& out) {
  switch (kind) {
    case ScalarKind::Int8: convertValues<std::int8_t>(bytes, swap, out); break;
    case ScalarKind::UInt8: convertValues<std::uint8_t>(bytes, swap, out); break;
    case ScalarKind::Int16: convertValues<std::int16_t>(bytes, swap, out); break;
    case ScalarKind::UInt16: convertValues<std::uint16_t>(bytes, swap, out); break;
    case ScalarKind::Int32: convertValues<std::int32_t>(bytes, swap, out); break;
    case ScalarKind::UInt32: convertValues<std::uint32_t>(bytes, swap, out); break;
    case ScalarKind::Float32: convertValues<float>(bytes, swap, out); break;
    case ScalarKind::Float64: convertValues<double>(bytes, swap, out); break;
  }
}

}  // namespace at::detail
