// The volume commands of anatomy-tutor, run as a user would: datasets, structures, info, slice.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "cli_checks.h"
#include "test_support.h"
#include "volume/mask.h"
#include "volume/phantom.h"
#include "volume/png_image.h"

using namespace at;
using nlohmann::json;

namespace {

std::string quoted(const std::string& s) { return "'" + s + "'"; }

using test::checkOneLineError;

std::uint8_t srgb8(float linear) {
  const double c = std::clamp(double(linear), 0.0, 1.0);
  const double s = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
  return std::uint8_t(std::lround(255 * s));
}

}  // namespace

TEST_CASE("every volume command answers --help with its usage and exit status 0") {
  for (const std::string cmd : {"datasets", "structures", "info", "slice"}) {
    CAPTURE(cmd);
    const auto r = test::runApp(cmd + " --help");
    CHECK(r.exitCode == 0);
    CHECK(r.out.find("usage: anatomy-tutor " + cmd) != std::string::npos);
  }
}

TEST_CASE("datasets lists the built-in phantom, as text and as JSON") {
  auto r = test::runApp("datasets");
  CHECK(r.exitCode == 0);
  CHECK(r.out.find("phantom") != std::string::npos);
  CHECK(r.out.find("Temporal-bone phantom (synthetic)") != std::string::npos);
  r = test::runApp("datasets --json");
  REQUIRE(r.exitCode == 0);
  const json j = json::parse(r.out);
  REQUIRE(j["datasets"].size() >= 1);
  CHECK(j["datasets"][0]["id"] == "phantom");
}

TEST_CASE("structures phantom lists the temporal-bone structures with their voxel counts") {
  auto r = test::runApp("structures phantom");
  CHECK(r.exitCode == 0);
  for (const char* id : {"cochlea", "vestibule", "lateral_semicircular_canal", "facial_nerve", "stapes",
                         "temporal_line"})
    CHECK(r.out.find(id) != std::string::npos);
  CHECK(r.out.find("Facial nerve") != std::string::npos);

  // JSON counts equal the phantom's own labels.
  r = test::runApp("structures phantom:64 --json");
  REQUIRE(r.exitCode == 0);
  const json j = json::parse(r.out);
  CHECK(j["dataset"] == "phantom:64");
  PhantomOptions options;
  options.size = 64;
  const Dataset ds = makePhantom(options);
  REQUIRE(j["structures"].size() == ds.structures.size());
  for (std::size_t i = 0; i < ds.structures.size(); ++i) {
    const Structure& s = ds.structures[i];
    CHECK(j["structures"][i]["id"] == s.id);
    CHECK(j["structures"][i]["label"] == s.label);
    CHECK(j["structures"][i]["voxels"].get<std::size_t>() == measureLabel(ds.labels, s.label).voxelCount);
  }
}

TEST_CASE("slice writes a PNG of the right size with the cochlea in its colour where the cochlea is") {
  PhantomOptions options;
  options.size = 128;
  const Dataset ds = makePhantom(options);
  const Structure* cochlea = ds.findStructure("cochlea");
  REQUIRE(cochlea);
  const MaskStats st = measureLabel(ds.labels, cochlea->label);
  const int k = int(std::lround(ds.labels.geometry.patientToIndex(st.centroidMm)[2]));

  test::TempDir dir;
  const std::string solid = (dir / "solid.png").string(), blended = (dir / "blended.png").string();
  auto r = test::runApp("slice phantom:128 --axis z --index " + std::to_string(k) + " --out " + quoted(solid) +
                        " --alpha 1");
  REQUIRE(r.exitCode == 0);
  r = test::runApp("slice phantom:128 --axis z --index " + std::to_string(k) + " --out " + quoted(blended));
  REQUIRE(r.exitCode == 0);
  auto a = readPng(solid), b = readPng(blended);
  REQUIRE(a.has_value());
  REQUIRE(b.has_value());
  CHECK(a->width == 128);
  CHECK(a->height == 128);

  const std::uint8_t want[3] = {srgb8(cochlea->colour[0]), srgb8(cochlea->colour[1]), srgb8(cochlea->colour[2])};
  int cochleaPixels = 0, greyPixels = 0;
  for (int j = 0; j < 128; ++j)
    for (int i = 0; i < 128; ++i) {
      const std::uint16_t label = ds.labels.at(i, j, k);
      const std::uint8_t* solidPx = a->pixel(i, j);  // axial: column i, row j
      const std::uint8_t* blendPx = b->pixel(i, j);
      if (label == cochlea->label) {
        ++cochleaPixels;
        CHECK(solidPx[0] == want[0]);
        CHECK(solidPx[1] == want[1]);
        CHECK(solidPx[2] == want[2]);
        CHECK(blendPx[0] > blendPx[2]);  // orange over grey stays warm
      } else if (label == 0) {
        greyPixels += solidPx[0] == solidPx[1] && solidPx[1] == solidPx[2];
      }
    }
  CHECK(cochleaPixels > 0);
  CHECK(greyPixels > 128 * 128 / 2);

  // A sagittal slice: columns along j, rows along k.
  const std::string sagittal = (dir / "sagittal.png").string();
  r = test::runApp("slice phantom:32 --axis x --index 3 --out " + quoted(sagittal));
  REQUIRE(r.exitCode == 0);
  auto c = readPng(sagittal);
  REQUIRE(c.has_value());
  CHECK(c->width == 32);
  CHECK(c->height == 32);
}

TEST_CASE("slice --plane draws patient orientation and prints the edge letters, for LPS and RAS files alike") {
  test::TempDir dir;
  // LPS data: --plane axial is the voxel order of --axis z, with the radiological letters.
  const std::string planeOut = (dir / "plane.png").string(), axisOut = (dir / "axis.png").string();
  auto r = test::runApp("slice phantom:32 --plane axial --index 12 --out " + quoted(planeOut));
  REQUIRE(r.exitCode == 0);
  CHECK(r.out.find("left R, right L, top A, bottom P") != std::string::npos);
  REQUIRE(test::runApp("slice phantom:32 --axis z --index 12 --out " + quoted(axisOut)).exitCode == 0);
  auto a = readPng(planeOut), b = readPng(axisOut);
  REQUIRE(a.has_value());
  REQUIRE(b.has_value());
  CHECK(a->rgb == b->rgb);
  r = test::runApp("slice phantom:32 --plane sagittal --index 3 --out " + quoted(planeOut));
  REQUIRE(r.exitCode == 0);
  CHECK(r.out.find("left A, right P, top S, bottom I") != std::string::npos);
  // The RAS-affine NIfTI: raw voxel order puts anterior at the bottom; --plane puts it on top.
  if (test::requireSharedData("seg_dicom.nii.gz")) {
    const std::string nifti = quoted(test::sharedData("totalsegmentator/seg_dicom.nii.gz").string());
    r = test::runApp("slice --volume " + nifti + " --axis z --index 10 --out " + quoted(axisOut));
    REQUIRE(r.exitCode == 0);
    CHECK(r.out.find("top P, bottom A") != std::string::npos);
    r = test::runApp("slice --volume " + nifti + " --plane coronal --index 300 --out " + quoted(planeOut));
    REQUIRE(r.exitCode == 0);
    CHECK(r.out.find("left R, right L, top S, bottom I") != std::string::npos);
  }
  checkOneLineError(test::runApp("slice phantom:32 --plane oblique --index 3 --out " + quoted(planeOut)), "--plane");
  checkOneLineError(test::runApp("slice phantom:32 --plane axial --axis z --index 3 --out " + quoted(planeOut)), "not both");
  checkOneLineError(test::runApp("slice phantom:32 --index 3 --out " + quoted(planeOut)), "--plane");
}

TEST_CASE("bad arguments to the volume commands fail with one line naming the problem") {
  test::TempDir dir;
  const std::string out = quoted((dir / "x.png").string());
  checkOneLineError(test::runApp("structures nosuchdataset"), "nosuchdataset");
  checkOneLineError(test::runApp("structures"), "missing DATASET");
  checkOneLineError(test::runApp("structures phantom:8"), "16 to 1024");
  checkOneLineError(test::runApp("structures phantom --labels x.nii.gz"), "--labels");
  checkOneLineError(test::runApp("slice phantom:32 --axis z --index 32 --out " + out), "outside 0 … 31");
  checkOneLineError(test::runApp("slice phantom:32 --axis z --index -1 --out " + out), "outside 0 … 31");
  checkOneLineError(test::runApp("slice phantom:32 --axis w --index 3 --out " + out), "--axis");
  checkOneLineError(test::runApp("slice phantom:32 --axis z --index three --out " + out), "--index");
  checkOneLineError(test::runApp("slice phantom:32 --axis z --index 3"), "--out");
  checkOneLineError(test::runApp("slice phantom:32 --axis z --index 3 --window 400 --out " + out), "--window");
  checkOneLineError(test::runApp("slice phantom:32 --axis z --index 3 --bogus --out " + out), "--bogus");
  checkOneLineError(test::runApp("slice phantom:32 --axis z --index 3 --out " +
                                 quoted((dir / "no_such_dir" / "x.png").string())),
                    "no_such_dir");
  checkOneLineError(test::runApp("datasets extra"), "extra");
  checkOneLineError(test::runApp("info"), "missing FILE");
  checkOneLineError(test::runApp("info " + quoted((dir / "missing.nii.gz").string())), "missing.nii.gz");
}

TEST_CASE("info describes the real NIfTI CT, its label map and the DICOM series") {
  if (!test::requireSharedData("info on real CT")) return;
  const std::string ct = quoted(test::sharedData("totalsegmentator/ct_small.nii.gz").string());
  const std::string seg = quoted(test::sharedData("totalsegmentator/seg_small.nii.gz").string());
  const std::string names = quoted(test::sharedData("totalsegmentator/labels.json").string());

  auto r = test::runApp("info " + ct);
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("122x101x30") != std::string::npos);
  CHECK(r.out.find("HU range") != std::string::npos);
  CHECK(r.out.find("int16") != std::string::npos);

  r = test::runApp("info " + ct + " --json");
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  json j = json::parse(r.out);
  CHECK(j["dimensions"] == json::array({122, 101, 30}));
  CHECK(j["value_range"][0].get<double>() < -500);  // air in HU
  CHECK(j["value_range"][1].get<double>() > 500);   // bone

  r = test::runApp("info " + seg + " --names " + names + " --json");
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  j = json::parse(r.out);
  CHECK(j["kind"] == "label map");
  bool liver = false;
  for (const auto& l : j["labels"]) liver = liver || (l["name"] == "liver" && l["voxels"].get<std::size_t>() > 0);
  CHECK(liver);

  r = test::runApp("info " + ct + " --labels " + seg + " --names " + names);
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("liver") != std::string::npos);

  r = test::runApp("info " + quoted(test::sharedData("totalsegmentator/ct_dicom").string()) + " --json");
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  j = json::parse(r.out);
  CHECK(j["dimensions"] == json::array({512, 512, 20}));
  CHECK(j["spacing_mm"][0].get<double>() == doctest::Approx(0.977).epsilon(0.01));
  CHECK(j["spacing_mm"][2].get<double>() == doctest::Approx(2.0).epsilon(0.01));
}
