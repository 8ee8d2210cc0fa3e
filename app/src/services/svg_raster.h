// SVG documents as pixels, through librsvg and cairo (the renderer GNOME uses for SVG): text,
// strokes and fills are drawn as a browser would, fonts from fontconfig.
#pragma once

#include <string>

#include "core/error.h"
#include "volume/png_image.h"

namespace at::app {

// Renders `svg` at `scale` × its intrinsic size (width/height attributes, in pixels) onto a white
// background. Errors: the text is not SVG librsvg can parse, it has no size, or the image would be
// empty or larger than 16384 pixels a side.
Result<RgbImage> rasteriseSvg(const std::string& svg, double scale = 1.0);

}  // namespace at::app
