// --intercept/--slope on a dataset from files: VTK's headsq NRRD stores CT numbers with air at 0
// (no rescale in its header), so it loads as plain intensities; with --intercept -1024 its values
// reach air and it becomes CT in HU (the HU grey window). Bad values are one-line errors naming the
// option; built-in datasets refuse the options.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "cli_checks.h"
#include "test_support.h"

using namespace at;

TEST_CASE("slice: --intercept -1024 turns a CT stored without its rescale into HU; bad values are refused") {
  if (!test::requireSharedData("headsq NRRD") || !test::requireAppBinary("slice --intercept")) return;
  test::TempDir dir;
  const std::string nrrd = test::sharedData("headsq/nrrd/quarter.nhdr").string();
  const std::string out = (dir / "s.png").string();
  const std::string base = "slice \"" + nrrd + "\" --axis z --index 40 --out \"" + out + "\"";
  const auto plain = test::runApp(base);
  REQUIRE(plain.exitCode == 0);
  CHECK(plain.out.find("window 400,2000") == std::string::npos);  // plain: the histogram window
  const auto hu = test::runApp(base + " --intercept -1024");
  REQUIRE_MESSAGE(hu.exitCode == 0, hu.err);
  CHECK(hu.out.find("window 400,2000") != std::string::npos);  // HU: the CT grey window
  // Forced plain keeps plain intensities (shifted) even though they reach air.
  const auto forced = test::runApp(base + " --intercept -1024 --intensity plain");
  REQUIRE(forced.exitCode == 0);
  CHECK(forced.out.find("window 400,2000") == std::string::npos);
  test::checkOneLineError(test::runApp(base + " --intercept abc"), "--intercept: 'abc' is not a number");
  test::checkOneLineError(test::runApp(base + " --slope 0"), "--slope: must not be 0");
  test::checkOneLineError(test::runApp("slice phantom:32 --axis z --index 3 --out \"" + out + "\" --slope 2"),
                          "apply to datasets from files");
}

// The same options on import are kept with the dataset: every later open of its name reads the
// values as at import (a slice of the imported name is the file's with the options, byte for byte);
// a refused import leaves the database file byte-identical.
TEST_CASE("import: --intercept, --slope and --intensity are kept with the dataset; bad values store nothing") {
  if (!test::requireSharedData("headsq NRRD") || !test::requireAppBinary("import --intercept")) return;
  test::TempDir dir;
  const auto quoted = [](const std::filesystem::path& p) { return "'" + p.string() + "'"; };
  const std::string nrrd = quoted(test::sharedData("headsq/nrrd/quarter.nhdr"));
  const std::string db = quoted(dir / "t.db");
  const auto slice = [&](const std::string& dataset, const std::string& options, const std::string& png) {
    const auto r = test::runApp("slice " + dataset + " --db " + db + " --axis z --index 40 --out " + quoted(dir / png) + options);
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    return r.out;
  };
  REQUIRE(test::runApp("import --volume " + nrrd + " --name head_hu --intercept -1024 --db " + db).exitCode == 0);
  REQUIRE(test::runApp("import --volume " + nrrd + " --name head_plain --intercept -1024 --intensity plain --db " + db).exitCode == 0);
  REQUIRE(test::runApp("import --volume " + nrrd + " --name head_raw --db " + db).exitCode == 0);
  CHECK(slice("head_hu", "", "hu.png").find("window 400,2000") != std::string::npos);
  slice(nrrd, " --intercept -1024", "file_hu.png");
  CHECK(test::readFile(dir / "hu.png") == test::readFile(dir / "file_hu.png"));
  CHECK(slice("head_plain", "", "plain.png").find("window 400,2000") == std::string::npos);
  CHECK(slice("head_raw", "", "raw.png").find("window 400,2000") == std::string::npos);
  slice(nrrd, "", "file_raw.png");
  CHECK(test::readFile(dir / "raw.png") == test::readFile(dir / "file_raw.png"));
  // The options of an imported dataset are its own: giving them again is refused.
  test::checkOneLineError(test::runApp("slice head_hu --db " + db + " --axis z --index 40 --out " + quoted(dir / "x.png") +
                                       " --intercept 5"),
                          "apply to datasets from files");
  const std::string before = test::readFile(dir / "t.db");
  for (const auto& [options, message] :
       {std::pair{" --intercept abc", "--intercept: 'abc' is not a number"}, std::pair{" --slope 0", "--slope: must be a number other than 0 within ±1e12"},
        std::pair{" --slope 1e300", "--slope: must be a number other than 0 within ±1e12"},
        std::pair{" --intercept -1e300", "--intercept: must be a number within ±1e15"},
        std::pair{" --slope nan", "--slope: 'nan' is not a number"}, std::pair{" --intensity kelvin", "unknown 'kelvin'"}}) {
    CAPTURE(options);
    test::checkOneLineError(test::runApp("import --volume " + nrrd + " --name head_bad --db " + db + options), message);
    CHECK(test::readFile(dir / "t.db") == before);
  }
}

// headsq's voxels are 3.2 × 3.2 × 1.5 mm: its sagittal and coronal slices come out 2.1 × as wide
// as their voxel counts (the anatomy's proportions), its axial slice as it is; the phantom's cubic
// voxels give one pixel per voxel.
TEST_CASE("slice: pictures of anisotropic voxels have square pixels in mm") {
  if (!test::requireSharedData("headsq DICOM") || !test::requireAppBinary("slice square pixels")) return;
  test::TempDir dir;
  const std::string head = "'" + test::sharedData("headsq/dicom").string() + "'";
  const std::string out = "'" + (dir / "s.png").string() + "'";
  for (const auto& [plane, size] : {std::pair{"sagittal", "(137x93, pixels of 1.500 mm"}, std::pair{"coronal", "(137x93, pixels of 1.500 mm"},
                                    std::pair{"axial", "(64x64, pixels of 3.200 mm"}}) {
    const auto r = test::runApp("slice " + head + " --plane " + plane + " --index 20 --out " + out);
    CAPTURE(plane);
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.out.find(size) != std::string::npos);
  }
  const auto phantom = test::runApp("slice phantom:32 --plane coronal --index 10 --out " + out);
  REQUIRE(phantom.exitCode == 0);
  CHECK(phantom.out.find("(32x32, ") != std::string::npos);
}

// info takes an imported dataset's name too: its volume file as imported, with its values read as
// the other commands read them (the import's --intercept shown and applied: the HU range, not the
// stored one), its checksum checked, and the file options refused.
TEST_CASE("info DATASET describes an imported dataset as it is read, with its load options") {
  if (!test::requireSharedData("headsq NRRD") || !test::requireAppBinary("info DATASET")) return;
  test::TempDir dir;
  const auto quoted = [](const std::filesystem::path& p) { return "'" + p.string() + "'"; };
  // A copy of the NRRD (header and its 93 data files), so one can be changed after the import.
  const std::filesystem::path copy = dir / "headsq";
  std::filesystem::copy(test::sharedData("headsq/nrrd"), copy);
  const std::string nrrd = quoted(copy / "quarter.nhdr");
  const std::string db = quoted(dir / "t.db");
  REQUIRE(test::runApp("import --volume " + nrrd + " --name head_hu --intercept -1024 --db " + db).exitCode == 0);
  REQUIRE(test::runApp("import --volume " + nrrd + " --name head_raw --db " + db).exitCode == 0);

  const auto hu = test::runApp("info head_hu --db " + db);
  REQUIRE_MESSAGE(hu.exitCode == 0, hu.err);
  CHECK(hu.out.find("dataset:     head_hu (human, imported ") != std::string::npos);
  CHECK(hu.out.find("values read with --intercept -1024)") != std::string::npos);
  CHECK(hu.out.find("path:        " + (copy / "quarter.nhdr").string()) != std::string::npos);
  CHECK(hu.out.find("intensity:   Hounsfield units") != std::string::npos);
  CHECK(hu.out.find("HU range:    -1024.0 … 2902.0") != std::string::npos);  // the file stores 0 … 3926
  const auto raw = test::runApp("info head_raw --db " + db);
  REQUIRE(raw.exitCode == 0);
  CHECK(raw.out.find("values read as stored)") != std::string::npos);
  CHECK(raw.out.find("intensity:   plain intensities") != std::string::npos);
  CHECK(raw.out.find("value range: 0.0 … 3926.0") != std::string::npos);
  const auto asJson = test::runApp("info head_hu --json --db " + db);
  REQUIRE(asJson.exitCode == 0);
  const auto j = nlohmann::json::parse(asJson.out);
  CHECK(j.at("dataset").at("name") == "head_hu");
  CHECK(j.at("dataset").at("load_options") == "--intercept -1024");
  CHECK(j.at("intensity").at("unit") == "HU");
  CHECK(j.at("value_range").at(0).get<double>() == -1024.0);

  // File options belong to files; an unknown name says what was looked for.
  test::checkOneLineError(test::runApp("info head_hu --labels x.nii --db " + db), "applies to files, not to imported 'head_hu'");
  test::checkOneLineError(test::runApp("info head_nothing --db " + db), "no such file or folder, scan or imported dataset");
  // A volume changed since its import is refused, naming the dataset and the file.
  { std::ofstream(copy / "quarter.40", std::ios::binary | std::ios::app) << "x"; }
  test::checkOneLineError(test::runApp("info head_hu --db " + db), "dataset 'head_hu': its volume");
}

// A fetched scan is read one way (its entry's); the options that would read a file another way are
// refused in one line by every command, before anything is read or written, fetched or not.
TEST_CASE("A fetched scan refuses the options that read a file another way, in one line, writing nothing") {
  if (!test::requireAppBinary("fetched scan options")) return;
  test::TempDir dir;
  const std::string out = "'" + (dir / "out.png").string() + "'";
  const std::string field = "'" + (dir / "out.nii.gz").string() + "'";
  for (const std::string option : {"--intensity plain", "--intensity hu", "--intercept -1024", "--slope 2", "--modality MR",
                                   "--series 1.2.3", "--skip-unreadable", "--nrrd-data ."}) {
    CAPTURE(option);
    test::checkOneLineError(test::runApp("slice skull --axis z --index 3 --out " + out + " " + option),
                            "not to the fetched scan 'skull' (it is read as fetched)");
    test::checkOneLineError(test::runApp("wdt skull mandible --out " + field + " " + option),
                            "not to the fetched scan 'skull' (it is read as fetched)");
    const auto info = test::runApp("info skull " + option);
    if (option.rfind("--intercept", 0) == 0 || option.rfind("--slope", 0) == 0) {
      test::checkOneLineError(info, "unknown option");  // info describes the file as stored
    } else {
      test::checkOneLineError(info, "applies to volume files and folders, not to the fetched scan 'skull'");
    }
  }
  CHECK(std::filesystem::is_empty(dir.path()));
}
