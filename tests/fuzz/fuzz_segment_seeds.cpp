// Seeds files of `anatomy-tutor segment --seeds` through parseSeeds, then rasterised onto a small
// grid (rasteriseSeeds) and checked for two seeded labels, as the segment command does before
// growing. Every step returns a value or a one-line error naming the file.
#include "fuzz_support.h"
#include "segment/seeds.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string source = "seeds.json";
  const auto seeds = segment::parseSeeds(std::string(reinterpret_cast<const char*>(data), size), source);
  fuzz::checkResult(seeds, source);
  if (!seeds) return 0;
  // Round trip: what seedsToJson writes reads back.
  const auto again = segment::parseSeeds(segment::seedsToJson(*seeds), source);
  fuzz::expect(again.has_value(), "seedsToJson's text parses again");
  fuzz::expect(again->labels.size() == seeds->labels.size() && again->strokes.size() == seeds->strokes.size(),
               "the round trip keeps labels and strokes");

  Geometry grid;
  grid.dims = {24, 20, 16};
  grid.spacingMm = {1.0, 1.5, 2.0};
  grid.originMm = {-12, -15, 0};
  const auto raster = segment::rasteriseSeeds(*seeds, grid);
  if (!raster) {
    fuzz::checkError(raster.error(), "");
    return 0;
  }
  fuzz::expect(raster->perLabel.size() == seeds->labels.size(), "a seed count per label");
  for (std::size_t n = 0; n < raster->seeds.size(); ++n) {
    fuzz::expect(raster->seeds[n].index < grid.dims.count(), "seed voxels lie on the grid");
    fuzz::expect(n == 0 || raster->seeds[n - 1].index < raster->seeds[n].index, "seed voxels sorted, one label each");
  }
  const auto two = segment::requireTwoSeededLabels(*seeds, *raster);
  if (!two) fuzz::checkError(two.error(), "");
  return 0;
}
