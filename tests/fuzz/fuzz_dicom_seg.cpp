// DICOM SEG (binary Segmentation Storage) through loadDicomSeg: the input is one .dcm file.
#include "fuzz_image.h"
#include "volume/dicom_seg.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string path = fuzz::inputAsFile(data, size, "seg.dcm");
  auto loaded = loadDicomSeg(path, fuzz::loaderOptions());
  if (!fuzz::checkLoaded(loaded, path)) return 0;
  fuzz::checkResult(toLabelMap(*loaded, path), path);
  return 0;
}
