// PNG writing and reading (libpng).
#include <doctest/doctest.h>

#include <fstream>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <random>

#include <zlib.h>

#include "test_support.h"
#include "volume/png_image.h"

using namespace at;

TEST_CASE("a random RGB image survives a PNG round trip byte for byte") {
  std::mt19937_64 rng(test::freshSeed("png round trip"));
  for (auto [w, h] : {std::pair{1, 1}, std::pair{7, 3}, std::pair{64, 48}}) {
    CAPTURE(w);
    CAPTURE(h);
    RgbImage image(w, h);
    for (auto& byte : image.rgb) byte = std::uint8_t(rng() & 0xFF);
    test::TempDir dir;
    const std::string path = (dir / "image.png").string();
    REQUIRE(writePng(path, image).has_value());
    auto back = readPng(path);
    REQUIRE(back.has_value());
    CHECK(back->width == w);
    CHECK(back->height == h);
    CHECK(back->rgb == image.rgb);
  }
}

TEST_CASE("PNG errors name the file and the problem") {
  test::TempDir dir;
  const std::string missing = (dir / "missing.png").string();
  auto r = readPng(missing);
  REQUIRE_FALSE(r.has_value());
  CHECK(r.error().message.find(missing) != std::string::npos);

  const std::string text = (dir / "text.png").string();
  std::ofstream(text) << "this is not a PNG file at all";
  r = readPng(text);
  REQUIRE_FALSE(r.has_value());
  CHECK(r.error().message.find("not a PNG") != std::string::npos);

  // A valid signature and header cut off in the middle: libpng's error comes back as a value.
  RgbImage image(32, 32);
  const std::string good = (dir / "good.png").string();
  REQUIRE(writePng(good, image).has_value());
  std::ifstream in(good, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string truncated = (dir / "truncated.png").string();
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, 40);
  r = readPng(truncated);
  REQUIRE_FALSE(r.has_value());
  CHECK(r.error().message.find(truncated) != std::string::npos);

  CHECK_FALSE(writePng((dir / "empty.png").string(), RgbImage{}).has_value());
  auto unwritable = writePng((dir / "no_such_dir" / "x.png").string(), image);
  REQUIRE_FALSE(unwritable.has_value());
  CHECK(unwritable.error().message.find("no_such_dir") != std::string::npos);
}

namespace {

std::uint32_t crc32Of(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xFFFFFFFFu;
}

std::string bigEndian32(std::uint32_t value) {
  return {char(value >> 24), char(value >> 16), char(value >> 8), char(value)};
}

std::string pngChunk(const std::string& type, const std::string& data) {
  return bigEndian32(std::uint32_t(data.size())) + type + data + bigEndian32(crc32Of(type + data));
}

}  // namespace

TEST_CASE("a PNG header claiming a huge image is refused before the image is allocated") {
  // 16384x16384 1-bit grey: its 805 MB of RGB fit the deflate ratio of a 40 KB file, which a
  // text chunk pads it to. The reader must refuse the size, not allocate it and fail later.
  const std::string header = bigEndian32(16384) + bigEndian32(16384) + std::string{1, 0, 0, 0, 0};
  const std::string bytes = std::string("\x89PNG\r\n\x1a\n", 8) + pngChunk("IHDR", header) +
                            pngChunk("tEXt", "Comment" + std::string(1, '\0') + std::string(40000, 'x')) +
                            pngChunk("IDAT", std::string("\x78\x9c", 2));
  test::TempDir dir;
  const std::string path = (dir / "huge.png").string();
  std::ofstream(path, std::ios::binary) << bytes;
  auto r = readPng(path);
  REQUIRE_FALSE(r.has_value());
  CHECK(r.error().message.find(path) != std::string::npos);
  CHECK(r.error().message.find("16384x16384") != std::string::npos);
  CHECK(r.error().message.find("pixels an image may have") != std::string::npos);
}

TEST_CASE("text chunks are skipped unread: 300 compressed comments do not inflate into memory") {
  // A 4x3 RGB image with 300 zTXt chunks
  // of 7.7 KB, each inflating to 7.9 MB (under libpng's 8 MB default per chunk). libpng kept every
  // inflated text until the read ended: a 2.3 GB peak from a 2.3 MB file (the fuzz campaign's
  // out-of-memory). Read in a child process, so its peak resident size is its own.
  // Written here (2.3 MB; the repository keeps no such file): 300 copies of one compressed comment.
  std::string comment(7'900'000, 'A');
  uLongf packedSize = compressBound(uLong(comment.size()));
  std::string packed(packedSize, '\0');
  REQUIRE(compress2(reinterpret_cast<Bytef*>(packed.data()), &packedSize, reinterpret_cast<const Bytef*>(comment.data()),
                    uLong(comment.size()), 9) == Z_OK);
  packed.resize(packedSize);
  std::string rows;
  for (int y = 0; y < 3; ++y) {
    rows += '\0';
    for (int x = 0; x < 4; ++x) rows += std::string(3, char((x * 60 + y * 20) % 256));
  }
  uLongf rowsSize = compressBound(uLong(rows.size()));
  std::string idat(rowsSize, '\0');
  REQUIRE(compress2(reinterpret_cast<Bytef*>(idat.data()), &rowsSize, reinterpret_cast<const Bytef*>(rows.data()),
                    uLong(rows.size()), 9) == Z_OK);
  idat.resize(rowsSize);
  std::string bytes = std::string("\x89PNG\r\n\x1a\n", 8) +
                      pngChunk("IHDR", bigEndian32(4) + bigEndian32(3) + std::string{8, 2, 0, 0, 0});
  for (int i = 0; i < 300; ++i)
    bytes += pngChunk("zTXt", "Comment" + std::to_string(i) + std::string(2, '\0') + packed);
  bytes += pngChunk("IDAT", idat) + pngChunk("IEND", "");
  test::TempDir dir;
  const std::string path = (dir / "many-inflating-text-chunks.png").string();
  std::ofstream(path, std::ios::binary) << bytes;
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    rusage before{}, after{};
    getrusage(RUSAGE_SELF, &before);
    auto image = readPng(path);
    getrusage(RUSAGE_SELF, &after);
    const long grownMb = (after.ru_maxrss - before.ru_maxrss) / 1024;
    const bool pixelsRight = image && image->width == 4 && image->height == 3 && image->pixel(1, 2)[0] == 100;
    _exit(!pixelsRight ? 2 : grownMb > 200 ? 3 : 0);
  }
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  REQUIRE(WIFEXITED(status));
  CHECK_MESSAGE(WEXITSTATUS(status) != 2, "the pixels were not read right");
  CHECK_MESSAGE(WEXITSTATUS(status) != 3, "reading the file grew the peak resident size by more than 200 MB");
  CHECK(WEXITSTATUS(status) == 0);
}
