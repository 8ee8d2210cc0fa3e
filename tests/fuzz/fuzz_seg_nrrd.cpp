// 3D Slicer segmentations (.seg.nrrd) through loadNrrd and toLabelMap, as `--labels` opens them:
// one layer (as writeSegNrrd and Slicer write them) or several layers of overlapping segments
// merged into one label map. The corpus starts from writeSegNrrd's output and hand-made layered
// files (at_fuzz_seeds), apart from fuzz_nrrd's images.
#include "fuzz_image.h"
#include "volume/nrrd_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string path = fuzz::inputAsFile(data, size, "labels.seg.nrrd");
  auto loaded = loadNrrd(path, fuzz::loaderOptions());
  if (!fuzz::checkLoaded(loaded, path)) return 0;
  auto labels = toLabelMap(*loaded, path);
  fuzz::checkResult(labels, path);
  if (labels) fuzz::expect(labels->voxels.size() == loaded->image.voxels.size(), "the label map covers every voxel");
  return 0;
}
