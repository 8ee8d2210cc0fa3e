// PNG through readPng (libpng with every transform to 8-bit RGB).
#include "fuzz_support.h"
#include "volume/png_image.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string path = fuzz::inputAsFile(data, size, "image.png");
  auto image = readPng(path);
  fuzz::checkResult(image, path);
  if (!image) return 0;
  fuzz::expect(image->rgb.size() == std::size_t(image->width) * std::size_t(image->height) * 3, "3 bytes per pixel");
  return 0;
}
