// PNG through libpng. libpng reports errors by longjmp; every libpng call that can fail runs in
// a function whose frame holds no C++ objects with destructors (setjmp/longjmp would skip them),
// and the png structs and FILE* are owned by RAII guards declared in the caller's frame.
#include "volume/png_image.h"

#include <png.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "core/atomic_file.h"
#include "core/regular_file.h"

namespace at {

namespace {

struct FileCloser {
  std::FILE* file = nullptr;
  ~FileCloser() {
    if (file) std::fclose(file);
  }
};

// libpng's error handler: keep the message, then longjmp back to the setjmp in the caller.
struct ErrorSink {
  char message[256] = "unknown libpng error";
};

void onPngError(png_structp png, png_const_charp msg) {
  auto* sink = static_cast<ErrorSink*>(png_get_error_ptr(png));
  if (sink) {
    std::snprintf(sink->message, sizeof sink->message, "%s", msg ? msg : "libpng error");
  }
  png_longjmp(png, 1);
}

void onPngWarning(png_structp, png_const_charp) {}

struct WriteGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~WriteGuard() {
    if (png) png_destroy_write_struct(&png, info ? &info : nullptr);
  }
};

struct ReadGuard {
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~ReadGuard() {
    if (png) png_destroy_read_struct(&png, info ? &info : nullptr, nullptr);
  }
};

// The encoded PNG is built in memory and written in one go (AtomicFile): libpng's own FILE* output
// would leave half a file behind on a full disk.
void appendToString(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), length);
}

void flushNothing(png_structp) {}

// Returns false after a libpng error (message in sink). No C++ objects with destructors live in
// this frame; `rows` and `out` are owned by the caller.
bool writeRows(WriteGuard& g, std::string* out, int width, int height, png_bytep* rows) {
  if (setjmp(png_jmpbuf(g.png))) return false;
  png_set_write_fn(g.png, out, appendToString, flushNothing);
  png_set_IHDR(g.png, g.info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(g.png, g.info);
  png_write_image(g.png, rows);
  png_write_end(g.png, nullptr);
  return true;
}

// Reads the header and configures transforms to 8-bit RGB. Same frame rule as writeRows.
bool readHeader(ReadGuard& g, std::FILE* file, png_uint_32* width, png_uint_32* height) {
  if (setjmp(png_jmpbuf(g.png))) return false;
  png_init_io(g.png, file);
  png_set_sig_bytes(g.png, 8);
  // Only the pixels are used. Text, ICC-profile, suggested-palette and Exif chunks are skipped
  // unread: a compressed text chunk may inflate to megabytes, libpng keeps every one until the
  // read ends, and a file may hold hundreds (the fuzz campaign's 2 GB peak). Any other ancillary
  // chunk libpng stores is limited to 1 MiB and 64 chunks.
  static constexpr png_byte kSkippedChunks[] = {'t', 'E', 'X', 't', '\0', 'z', 'T', 'X', 't', '\0', 'i', 'T', 'X', 't', '\0',
                                                'i', 'C', 'C', 'P', '\0', 's', 'P', 'L', 'T', '\0', 'e', 'X', 'I', 'f', '\0'};
  png_set_keep_unknown_chunks(g.png, PNG_HANDLE_CHUNK_NEVER, kSkippedChunks, int(sizeof kSkippedChunks / 5));
  png_set_chunk_malloc_max(g.png, 1u << 20);
  png_set_chunk_cache_max(g.png, 64);
  png_read_info(g.png, g.info);
  *width = png_get_image_width(g.png, g.info);
  *height = png_get_image_height(g.png, g.info);
  const int colour = png_get_color_type(g.png, g.info);
  const int depth = png_get_bit_depth(g.png, g.info);
  if (depth == 16) png_set_strip_16(g.png);
  if (colour == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(g.png);
  if (colour == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(g.png);
  if (png_get_valid(g.png, g.info, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(g.png);
  if (colour == PNG_COLOR_TYPE_GRAY || colour == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(g.png);
  png_set_strip_alpha(g.png);
  png_read_update_info(g.png, g.info);
  return png_get_rowbytes(g.png, g.info) == std::size_t(*width) * 3;
}

bool readRows(ReadGuard& g, png_bytep* rows) {
  if (setjmp(png_jmpbuf(g.png))) return false;
  png_read_image(g.png, rows);
  png_read_end(g.png, nullptr);
  return true;
}

}  // namespace

Status writePng(const std::string& path, const RgbImage& image) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != std::size_t(image.width) * std::size_t(image.height) * 3)
    return fail(path + ": cannot write an empty or inconsistent image (" + std::to_string(image.width) + "x" +
                std::to_string(image.height) + ")");
  if (auto ok = checkOutputPath(path, path); !ok) return ok;
  ErrorSink sink;
  WriteGuard g;
  g.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &sink, onPngError, onPngWarning);
  if (!g.png) return fail(path + ": libpng could not start");
  g.info = png_create_info_struct(g.png);
  if (!g.info) return fail(path + ": libpng could not start");
  std::vector<png_bytep> rows(std::size_t(image.height));
  for (int y = 0; y < image.height; ++y)
    rows[std::size_t(y)] = const_cast<png_bytep>(image.pixel(0, y));
  std::string encoded;
  if (!writeRows(g, &encoded, image.width, image.height, rows.data()))
    return fail(path + ": cannot write PNG: " + sink.message);
  return writeFileAtomically(path, encoded);
}

Result<RgbImage> readPng(const std::string& path) {
  auto regular = openRegularFile(path, path);
  if (!regular) return tl::unexpected(regular.error());
  const std::uint64_t fileBytes = regular->sizeBytes;
  FileCloser file{fdopen(regular->fd.get(), "rb")};
  if (!file.file) return fail(ErrorKind::Io, path + ": cannot open file: " + std::strerror(errno));
  regular->fd.release();
  png_byte signature[8] = {};
  if (std::fread(signature, 1, 8, file.file) != 8 || png_sig_cmp(signature, 0, 8) != 0)
    return fail(path + ": not a PNG file (wrong signature)");
  ErrorSink sink;
  ReadGuard g;
  g.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &sink, onPngError, onPngWarning);
  if (!g.png) return fail(path + ": libpng could not start");
  g.info = png_create_info_struct(g.png);
  if (!g.info) return fail(path + ": libpng could not start");
  png_uint_32 width = 0, height = 0;
  if (!readHeader(g, file.file, &width, &height)) return fail(path + ": cannot read PNG: " + sink.message);
  constexpr png_uint_32 kMaxSide = 1u << 15;
  if (width == 0 || height == 0 || width > kMaxSide || height > kMaxSide)
    return fail(path + ": PNG size " + std::to_string(width) + "x" + std::to_string(height) + " is not supported");
  // Screenshots, figures and stimuli are at most a 4K frame (8.3 million pixels); a header claiming
  // more than kMaxPixels (48 MiB of RGB) is refused before anything is allocated.
  constexpr std::uint64_t kMaxPixels = std::uint64_t(1) << 24;
  if (std::uint64_t(width) * std::uint64_t(height) > kMaxPixels)
    return fail(path + ": PNG size " + std::to_string(width) + "x" + std::to_string(height) + " is more than the " +
                std::to_string(kMaxPixels) + " pixels an image may have");
  // Deflate inflates at most 1032:1, and a 1-bit grey pixel becomes 24 bits of RGB: a header claiming
  // more pixels than that is refused before the image is allocated.
  const double outputBytes = double(width) * double(height) * 3.0;
  if (outputBytes > double(fileBytes) * 1032.0 * 24.0)
    return fail(path + ": PNG size " + std::to_string(width) + "x" + std::to_string(height) +
                " is more than its " + std::to_string(fileBytes) + " bytes can hold");
  RgbImage image{int(width), int(height)};
  std::vector<png_bytep> rows(height);
  for (png_uint_32 y = 0; y < height; ++y) rows[y] = image.pixel(0, int(y));
  if (!readRows(g, rows.data())) return fail(path + ": cannot read PNG: " + sink.message);
  return image;
}

}  // namespace at
