// The seeds file: parsing (strict, errors naming the field), writing, rasterising strokes in mm.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>

#include "segment/seeds.h"
#include "test_support.h"

using namespace at;
using namespace at::segment;

namespace {

const char* kGood = R"({
  "schema": 1,
  "labels": [{"value": 0, "name": "background"}, {"value": 5, "name": "liver", "colour": [0.9, 0.2, 0.3]},
             {"value": 7, "name": "bone", "range": [300, 3000], "min_diameter_mm": 2}],
  "strokes": [{"label": "liver", "radius_mm": 1, "points": [[1, 2, 3], [4, 2, 3]]},
              {"label": 0, "points": [[-5, -5, 0]]},
              {"label": 7, "points": [[0, 0, 0]]}],
  "grow": {"weight": "gradient", "window": [-100, 400], "base": 0.01, "smoothing": 0.5}
})";

Geometry grid() {
  Geometry g;
  g.dims = {30, 30, 20};
  g.spacingMm = {0.5, 0.5, 1.0};
  g.originMm = {-7, -7, -5};
  return g;
}

void checkError(const std::string& json, const std::string& mustMention) {
  auto r = parseSeeds(json, "s.json");
  REQUIRE(!r);
  CAPTURE(r.error().message);
  CHECK(r.error().message.rfind("s.json: ", 0) == 0);
  CHECK(r.error().message.find(mustMention) != std::string::npos);
}

}  // namespace

TEST_CASE("A seeds file parses, writes back the same, and rasterises its strokes in mm") {
  auto seeds = parseSeeds(kGood, "s.json");
  REQUIRE(seeds);
  REQUIRE(seeds->labels.size() == 3);
  CHECK(seeds->labels[1].colour.has_value());
  CHECK(seeds->labels[2].range == std::array<double, 2>{300, 3000});
  CHECK(seeds->strokes[1].label == 0);
  CHECK(*seeds->grow.window == std::array<double, 2>{-100, 400});
  auto again = parseSeeds(seedsToJson(*seeds), "again.json");
  REQUIRE(again);
  CHECK(again->strokes.size() == 3);
  CHECK(seeds->grow.smoothing == 0.5);
  CHECK(again->grow.smoothing == 0.5);
  CHECK(again->strokes[0].pointsMm == seeds->strokes[0].pointsMm);
  CHECK(again->strokes[0].radiusMm == 1);

  auto raster = rasteriseSeeds(*seeds, grid());
  REQUIRE(raster);
  // The liver stroke: a 3 mm line with a 1 mm brush on 0.5 mm voxels: more voxels than the line.
  CHECK(raster->perLabel[1] > 7);
  CHECK(raster->perLabel[0] == 1);
  CHECK(std::is_sorted(raster->seeds.begin(), raster->seeds.end(),
                       [](const GrowthSeed& a, const GrowthSeed& b) { return a.index < b.index; }));
  CHECK(requireTwoSeededLabels(*seeds, *raster));
}

TEST_CASE("RAS coordinates are turned into LPS") {
  auto seeds = parseSeeds(R"({"space": "RAS", "labels": [{"value": 1, "name": "a"}],
                              "strokes": [{"label": "a", "points": [[10, 20, 30]]}]})",
                          "ras.json");
  REQUIRE(seeds);
  CHECK((seeds->strokes[0].pointsMm[0] == Vec3{-10, -20, 30}));
}

TEST_CASE("Bad seeds files and seeds are one-line errors naming the field, the label or the point") {
  checkError("[1, 2]", "expected a JSON object");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}], \"strokes\": [], \"colour\": 3}", "field 'colour' is not a known field");
  checkError("{\"labels\": [], \"strokes\": []}", "labels must be a non-empty list");
  checkError("{\"labels\": [{\"value\": 70000, \"name\": \"a\"}], \"strokes\": []}", "labels[0].value must be a label value");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}, {\"value\": 1, \"name\": \"b\"}], \"strokes\": []}",
             "labels[1].value 1 is listed twice");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}], \"strokes\": [{\"label\": \"kidney\", \"points\": [[0,0,0]]}]}",
             "strokes[0].label 'kidney' is not one of the labels (a)");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}], \"strokes\": [{\"label\": \"a\", \"points\": [[0,0]]}]}",
             "strokes[0].points[0] must be 3 numbers");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}], \"strokes\": [{\"label\": \"a\", \"points\": [[0,0,0]], "
             "\"radius_mm\": -1}]}",
             "strokes[0].radius_mm");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}], \"strokes\": [], \"grow\": {\"base\": 0}}", "grow.base must be");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}], \"strokes\": [], \"grow\": {\"smoothing\": 9}}",
             "grow.smoothing must be");
  checkError("{\"labels\": [{\"value\": 1, \"name\": \"a\"}], \"strokes\": [] ", "not valid JSON");

  auto outside = parseSeeds(R"({"labels": [{"value": 0, "name": "background"}, {"value": 1, "name": "a"}],
                                "strokes": [{"label": "a", "points": [[0, 0, 0], [0, 0, 400]]}]})",
                            "o.json");
  REQUIRE(outside);
  auto raster = rasteriseSeeds(*outside, grid());
  REQUIRE(!raster);
  CHECK(raster.error().message.find("strokes[0].points[1] (0.0, 0.0, 400.0) mm of label 'a' lies outside the volume") !=
        std::string::npos);

  // A point whose voxel index no int holds (the fuzz campaign's finding: the cast was undefined
  // and could wrap onto the grid) is refused like any other point outside.
  auto far = parseSeeds(R"({"labels": [{"value": 0, "name": "background"}, {"value": 1, "name": "a"}],
                            "strokes": [{"label": "a", "points": [[0, 0, 0], [0, -4.4e63, 0]]}]})",
                        "far.json");
  REQUIRE(far);
  auto farRaster = rasteriseSeeds(*far, grid());
  REQUIRE(!farRaster);
  CHECK(farRaster.error().message.find("strokes[0].points[1]") != std::string::npos);
  CHECK(farRaster.error().message.find("lies outside the volume") != std::string::npos);

  auto single = parseSeeds(R"({"labels": [{"value": 0, "name": "background"}, {"value": 1, "name": "a"}],
                               "strokes": [{"label": "a", "points": [[0, 0, 0]]}]})",
                           "one.json");
  REQUIRE(single);
  auto oneRaster = rasteriseSeeds(*single, grid());
  REQUIRE(oneRaster);
  auto two = requireTwoSeededLabels(*single, *oneRaster);
  REQUIRE(!two);
  CHECK(two.error().message.find("only label 'a' has strokes") != std::string::npos);
}

TEST_CASE("Seeds_LargeRadiiOnManyPoints_RefusedBeforeAnyPainting_SmallBrushesStillWork") {
  // 200 points of radius 100 mm (a 5.5 KB file) once ran for minutes: every point's box is the
  // whole volume. The visits are counted first and refused over the volume's voxel count.
  Geometry g;
  g.dims = {160, 160, 120};
  g.spacingMm = {0.5, 0.5, 0.5};
  const std::uint64_t seed = test::freshSeed("seeds cap");
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> x(1, 79), z(1, 59);
  const auto seedsWith = [&](int points, double radiusMm) {
    std::string json = R"({"schema": 1, "labels": [{"value": 0, "name": "background"}, {"value": 1, "name": "a"}],
                          "strokes": [)";
    for (int p = 0; p < points; ++p) {
      json += std::string(p ? "," : "") + R"({"label": )" + std::to_string(p % 2) + R"(, "radius_mm": )" +
              std::to_string(radiusMm) + R"(, "points": [[)" + std::to_string(x(random)) + "," + std::to_string(x(random)) +
              "," + std::to_string(z(random)) + "]]}";
    }
    auto parsed = parseSeeds(json + "]}", "big.json");
    REQUIRE(parsed);
    return *parsed;
  };
  auto refused = rasteriseSeeds(seedsWith(200, 100), g);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("radius_mm") != std::string::npos);
  CHECK(refused.error().message.find(std::to_string(seedVisitBudget(g.dims))) != std::string::npos);

  // Many small dots, as the desktop's brush writes them, stay well inside the budget.
  auto brushed = rasteriseSeeds(seedsWith(2000, 1.5), g);
  REQUIRE_MESSAGE(brushed, (brushed ? "" : brushed.error().message));
  CHECK(brushed->seeds.size() > 2000);
  CHECK(std::is_sorted(brushed->seeds.begin(), brushed->seeds.end(),
                       [](const GrowthSeed& a, const GrowthSeed& b) { return a.index < b.index; }));
  // Each seed voxel lies within its brush of some point of its label: spot-checked by count.
  CHECK(brushed->perLabel[0] + brushed->perLabel[1] == brushed->seeds.size());
}
