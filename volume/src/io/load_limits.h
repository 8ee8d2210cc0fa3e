// Shared by the loaders: the memory check every loader makes before allocating voxels.
//
// A load's peak is counted whole: the float image the loader returns, the 2-byte HU or label copy
// that every caller makes from it (toHuVolume, toLabelMap) while it is still alive, and the
// loader's own transient buffers (read pieces, decoded slices) — so that the peak never exceeds the
// limit the message names.
#pragma once

#include <cstddef>
#include <cstdio>
#include <string>

#include "core/error.h"
#include "volume/image_file.h"

namespace at::detail {

inline std::string byteCountText(double bytes) {
  char text[64];
  if (bytes < 1048576.0)
    std::snprintf(text, sizeof text, "%.0f bytes", bytes);
  else if (bytes < 1073741824.0)
    std::snprintf(text, sizeof text, "%.1f MiB", bytes / 1048576.0);
  else
    std::snprintf(text, sizeof text, "%.1f GiB", bytes / 1073741824.0);
  return text;
}

// True once the caller asked the load to stop (ImageLoadOptions::cancel).
inline bool loadCancelled(const ImageLoadOptions& options) {
  return options.cancel && options.cancel->load(std::memory_order_relaxed);
}
inline Error cancelledError(const std::string& path) { return Error{ErrorKind::Cancelled, path + ": loading cancelled"}; }

// Bytes per voxel of a load's result: the float image and its 2-byte HU or label copy.
inline constexpr double kResultBytesPerVoxel = sizeof(float) + 2;

// Fails if the load's peak — the float image, its HU/label copy and `transientBytes` of the
// loader's own buffers — exceeds options.maxBytes (or imageMemoryBudget() when 0).
inline Status checkImageFits(const std::string& path, const Dims& dims, double transientBytes,
                             const ImageLoadOptions& options) {
  MemoryBudget budget;
  if (options.maxBytes) {
    budget.bytes = options.maxBytes;
    budget.source = "the limit this load was given";
  } else {
    budget = imageMemoryBudget();
  }
  // In double: dimensions from a broken header may overflow size_t.
  const double voxels = double(dims.x) * double(dims.y) * double(dims.z);
  const double bytes = voxels * kResultBytesPerVoxel + transientBytes;
  if (bytes > double(budget.bytes))
    return fail(ErrorKind::Unavailable, path + ": image " + dims.toString() + " needs " + byteCountText(bytes) +
                " (float voxels, their HU or label copy and read buffers) but only " +
                byteCountText(double(budget.bytes)) + " may be used (memory limit: " + budget.source + ")");
  return {};
}

}  // namespace at::detail
