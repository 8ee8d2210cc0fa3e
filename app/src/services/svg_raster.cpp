#include "svg_raster.h"

#include <cairo.h>
#include <librsvg/rsvg.h>

#include <cmath>
#include <memory>

namespace at::app {

namespace {

struct GObjectUnref {
  void operator()(void* object) const { g_object_unref(object); }
};
struct SurfaceDestroy {
  void operator()(cairo_surface_t* surface) const { cairo_surface_destroy(surface); }
};
struct ContextDestroy {
  void operator()(cairo_t* cr) const { cairo_destroy(cr); }
};
struct ErrorFree {
  void operator()(GError* error) const { g_error_free(error); }
};

}  // namespace

Result<RgbImage> rasteriseSvg(const std::string& svg, double scale) {
  if (!(scale > 0)) return fail("rasterising SVG: scale must be positive");
  GError* rawError = nullptr;
  std::unique_ptr<RsvgHandle, GObjectUnref> handle(
      rsvg_handle_new_from_data(reinterpret_cast<const guint8*>(svg.data()), svg.size(), &rawError));
  std::unique_ptr<GError, ErrorFree> error(rawError);
  if (!handle) return fail("rasterising SVG: " + std::string(error ? error->message : "not an SVG document"));
  gdouble width = 0, height = 0;
  if (!rsvg_handle_get_intrinsic_size_in_pixels(handle.get(), &width, &height))
    return fail("rasterising SVG: the document has no width and height in pixels");
  const int w = int(std::lround(width * scale)), h = int(std::lround(height * scale));
  if (w <= 0 || h <= 0 || w > 16384 || h > 16384)
    return fail("rasterising SVG: " + std::to_string(w) + "x" + std::to_string(h) + " pixels is not a usable size");

  std::unique_ptr<cairo_surface_t, SurfaceDestroy> surface(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w, h));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS)
    return fail(ErrorKind::Io, "rasterising SVG: cannot allocate a " + std::to_string(w) + "x" + std::to_string(h) +
                                   " image");
  std::unique_ptr<cairo_t, ContextDestroy> cr(cairo_create(surface.get()));
  cairo_set_source_rgb(cr.get(), 1, 1, 1);
  cairo_paint(cr.get());
  const RsvgRectangle viewport{0, 0, double(w), double(h)};
  rawError = nullptr;
  if (!rsvg_handle_render_document(handle.get(), cr.get(), &viewport, &rawError)) {
    error.reset(rawError);
    return fail("rasterising SVG: " + std::string(error ? error->message : "librsvg could not draw it"));
  }
  cairo_surface_flush(surface.get());

  // ARGB32 is premultiplied, one native-endian 32-bit word per pixel; the white background makes
  // every pixel opaque, so the colour channels are the final colour.
  RgbImage image(w, h);
  const unsigned char* data = cairo_image_surface_get_data(surface.get());
  const int stride = cairo_image_surface_get_stride(surface.get());
  for (int y = 0; y < h; ++y) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + std::size_t(y) * std::size_t(stride));
    for (int x = 0; x < w; ++x) {
      const std::uint32_t argb = row[x];
      std::uint8_t* p = image.pixel(x, y);
      p[0] = std::uint8_t((argb >> 16) & 0xff);
      p[1] = std::uint8_t((argb >> 8) & 0xff);
      p[2] = std::uint8_t(argb & 0xff);
    }
  }
  return image;
}

}  // namespace at::app
