// Shared by the loaders: the memory check every loader makes before allocating voxels.
#pragma once

#include <cstddef>
#include <string>

#include "volume/error.h"
#include "volume/image_file.h"

namespace at::detail {

// Fails if the image's float voxels exceed options.maxBytes (or availableImageBytes() when 0).
inline Status checkImageFits(const std::string& path, const Dims& dims, const ImageLoadOptions& options) {
  const std::size_t limit = options.maxBytes ? options.maxBytes : availableImageBytes();
  // In double: dimensions from a broken header may overflow size_t.
  const double bytes = double(dims.x) * double(dims.y) * double(dims.z) * double(sizeof(float));
  if (bytes > double(limit))
    return fail(path + ": image " + dims.toString() + " needs " + std::to_string((long long)(bytes / 1048576.0)) +
                " MiB as float but only " + std::to_string(limit >> 20) + " MiB may be used");
  return {};
}

}  // namespace at::detail
