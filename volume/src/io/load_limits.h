// Shared by the loaders: the memory check every loader makes before allocating voxels.
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
  else
    std::snprintf(text, sizeof text, "%.1f MiB", bytes / 1048576.0);
  return text;
}

// True once the caller asked the load to stop (ImageLoadOptions::cancel).
inline bool loadCancelled(const ImageLoadOptions& options) {
  return options.cancel && options.cancel->load(std::memory_order_relaxed);
}
inline Error cancelledError(const std::string& path) { return Error{ErrorKind::Cancelled, path + ": loading cancelled"}; }

// Fails if the image's float voxels exceed options.maxBytes (or availableImageBytes() when 0).
inline Status checkImageFits(const std::string& path, const Dims& dims, const ImageLoadOptions& options) {
  const std::size_t limit = options.maxBytes ? options.maxBytes : availableImageBytes();
  // In double: dimensions from a broken header may overflow size_t.
  const double bytes = double(dims.x) * double(dims.y) * double(dims.z) * double(sizeof(float));
  if (bytes > double(limit))
    return fail(path + ": image " + dims.toString() + " needs " + byteCountText(bytes) + " as float but only " +
                byteCountText(double(limit)) + " may be used (memory limit)");
  return {};
}

}  // namespace at::detail
