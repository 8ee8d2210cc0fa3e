// A course package carries its dataset's values, not only its voxels: on the student's machine the
// dataset reads in the author's unit with the author's values and grey window (`info NAME --json`
// alike, slices byte-identical), for volumes whose file read by itself would say otherwise — a
// 16-bit µCT stored shifted into int16, plain intensities that reach −500, a CT cropped to no air,
// and referenced files the author read with --intercept, --slope or --intensity. A package that
// needs no reading stays format version 1, which earlier programs read. An included MR keeps its
// modality, and with it the note that density-weighted distances assume CT.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>

#include <nlohmann/json.hpp>

#include "../package/tar_files.h"
#include "../volume/dicom_test_files.h"
#include "cli_checks.h"
#include "desktop_script.h"
#include "intensity_notes.h"
#include "synthetic_scans.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/nrrd_io.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

nlohmann::json run(const std::string& args) {
  const auto r = test::runApp(args);
  REQUIRE_MESSAGE(r.exitCode == 0, args << ": " << r.err);
  return r.out.empty() || r.out[0] != '{' ? nlohmann::json(r.out) : nlohmann::json::parse(r.out);
}

// What a user sees of a dataset's values: the unit, the values' range and the grey window (the
// stored form may differ between the author's file and the package's int16 NRRD).
nlohmann::json valuesSeen(const std::string& name, const fs::path& db) {
  const nlohmann::json info = run("info " + name + " --json --db " + quoted(db));
  return {{"unit", info["intensity"]["unit"]}, {"window", info["intensity"]["window"]}, {"values", info["value_range"]},
          {"labels", info["labels"]}};
}

// A volume of the synthetic µCT's shape with values `grey·scale + offset` written as `kind`, and
// its label map (1 bone, 2 the soft tissue inside) and names in `dir`.
void writeScan(const fs::path& dir, double scale, double offset, ScalarKind kind) {
  FloatVolume v = test::syntheticMicroCt({40, 36, 30});
  FloatVolume labels(v.geometry, 0.0f);
  for (std::size_t n = 0; n < v.voxels.size(); ++n) {
    labels.voxels[n] = v.voxels[n] > 150 ? 1.0f : (v.voxels[n] > 50 ? 2.0f : 0.0f);
    v.voxels[n] = float(v.voxels[n] * scale + offset);
  }
  REQUIRE(writeNrrd((dir / "scan.nrrd").string(), v, kind));
  REQUIRE(writeNrrd((dir / "labels.nrrd").string(), labels, ScalarKind::UInt16));
  std::ofstream(dir / "names.json") << R"({"1": "bone", "2": "soft tissue"})";
}

struct Shared {
  nlohmann::json author, student;
  int formatVersion = 0;
  nlohmann::json reading;  // the manifest's dataset.reading, or null
  std::string authorSlice, studentSlice;
};

// Imports the scan in `dir` with `importOptions`, makes a course on it, exports it (with
// `exportOptions`) and imports the package into a fresh database, giving the scan where it is
// referenced; what the author and the student see.
Shared shareScan(const test::TempDir& dir, const std::string& importOptions, const std::string& exportOptions) {
  const fs::path author = dir / "a.db", student = dir / "s.db", package = dir / "c.atcourse";
  run("import --volume " + quoted(dir / "scan.nrrd") + " --labels " + quoted(dir / "labels.nrrd") + " --names " +
      quoted(dir / "names.json") + " --name scan --db " + quoted(author) + importOptions);
  run("course new tour --dataset scan --db " + quoted(author));
  run("course export tour --out " + quoted(package) + " --db " + quoted(author) + exportOptions);
  const bool referenced = exportOptions.find("--reference-volume") != std::string::npos;
  run("course import " + quoted(package) + (referenced ? " --volume " + quoted(dir / "scan.nrrd") : "") + " --db " + quoted(student));
  Shared out;
  out.author = valuesSeen("scan", author);
  out.student = valuesSeen("scan", student);
  auto entries = test::readTar(package);
  const auto manifest = nlohmann::json::parse(test::findEntry(entries, "manifest.json")->data);
  out.formatVersion = manifest["format_version"].get<int>();
  out.reading = manifest["dataset"].value("reading", nlohmann::json());
  for (const auto& [db, png] : {std::pair{author, dir / "a.png"}, std::pair{student, dir / "s.png"}})
    run("slice scan --axis z --index 15 --out " + quoted(png) + " --db " + quoted(db));
  out.authorSlice = test::readFile(dir / "a.png");
  out.studentSlice = test::readFile(dir / "s.png");
  return out;
}

// The real head CT's DICOM series (../shared/data/headsq/dicom) copied into `folder`, each file
// changed by `edit` when one is given (DCMTK).
void copyHeadSeries(const fs::path& folder, const std::function<void(DcmDataset&)>& edit = {}) {
  fs::create_directories(folder);
  for (const auto& e : fs::directory_iterator(test::sharedData("headsq/dicom"))) {
    if (e.path().extension() != ".dcm") continue;
    if (edit)
      REQUIRE(test::rewriteDicom(e.path(), folder / e.path().filename(), edit));
    else
      fs::copy_file(e.path(), folder / e.path().filename());
  }
}

// The author's side: `volume` imported as dataset `name` into `db` with `labels` (label 1, named
// "block") and `importOptions`, and a course "tour" on it.
void authorCourse(const fs::path& dir, const fs::path& volume, const FloatVolume& labels, const std::string& name,
                  const std::string& importOptions, const fs::path& db) {
  REQUIRE(writeNrrd((dir / "labels.nrrd").string(), labels, ScalarKind::UInt16));
  std::ofstream(dir / "names.json") << R"({"1": "block"})";
  run("import --volume " + quoted(volume) + " --labels " + quoted(dir / "labels.nrrd") + " --names " +
      quoted(dir / "names.json") + " --name " + name + importOptions + " --db " + quoted(db));
  run("course new tour --dataset " + name + " --db " + quoted(db));
}

void checkSameValues(const Shared& s) {
  CHECK(s.student == s.author);
  CHECK(s.studentSlice == s.authorSlice);
}

}  // namespace

TEST_CASE("CourseCli_PackagedDataset_ReadsWithTheAuthorsUnitValuesAndWindow") {
  if (!test::requireAppBinary("course packages")) return;
  SUBCASE("a 16-bit µCT above 32767, included: stored shifted into int16, read back as plain intensities") {
    test::TempDir dir("at-values");
    writeScan(dir.path(), 256, 100, ScalarKind::UInt16);  // up to 65380
    const Shared s = shareScan(dir, "", "");
    CHECK(s.author["unit"] == "plain");
    CHECK(s.author["values"][1].get<double>() > 60000);
    checkSameValues(s);
    CHECK(s.formatVersion == 2);
    CHECK(s.reading["intensity"] == "plain");
  }
  SUBCASE("plain intensities down to -2000 (--intensity plain), included") {
    test::TempDir dir("at-values");
    writeScan(dir.path(), 10, -2000, ScalarKind::Int16);
    const Shared s = shareScan(dir, " --intensity plain", "");
    CHECK(s.author["unit"] == "plain");
    checkSameValues(s);
    CHECK(s.reading == nlohmann::json{{"intensity", "plain"}});
  }
  SUBCASE("a CT cropped to no air (--intensity hu), included") {
    test::TempDir dir("at-values");
    writeScan(dir.path(), 4, 0, ScalarKind::Int16);  // 0 … 1020 HU
    const Shared s = shareScan(dir, " --intensity hu", "");
    CHECK(s.author["unit"] == "HU");
    checkSameValues(s);
    CHECK(s.reading == nlohmann::json{{"intensity", "hu"}});
  }
  SUBCASE("a CT stored as HU + 1024 read with --intercept -1024: included needs no reading, referenced keeps the options") {
    test::TempDir dir("at-values");
    writeScan(dir.path(), 8, 0, ScalarKind::Int16);  // air near 110, bone near 1570: HU + 1024
    const Shared included = shareScan(dir, " --intercept -1024", "");
    CHECK(included.author["unit"] == "HU");
    checkSameValues(included);
    CHECK(included.formatVersion == 1);
    CHECK(included.reading.is_null());
    test::TempDir again("at-values");
    writeScan(again.path(), 8, 0, ScalarKind::Int16);
    const Shared referenced = shareScan(again, " --intercept -1024", " --reference-volume");
    CHECK(referenced.author == included.author);
    checkSameValues(referenced);
    CHECK(referenced.reading == nlohmann::json{{"intensity", "auto"}, {"intercept", -1024.0}});
  }
  SUBCASE("plain intensities read with --slope 0.5, referenced and included") {
    for (const char* exportOptions : {" --reference-volume", ""}) {
      CAPTURE(exportOptions);
      test::TempDir dir("at-values");
      writeScan(dir.path(), 1, 0, ScalarKind::UInt8);
      const Shared s = shareScan(dir, " --slope 0.5", exportOptions);
      CHECK(s.author["unit"] == "plain");
      CHECK(s.author["values"][1].get<double>() <= 127.5);
      checkSameValues(s);
      CHECK(s.reading["slope"] == 0.5);
    }
  }
}

// A referenced DICOM folder the author imported with --skip-unreadable (a truncated file among
// the slices): the student's `course import` has no such option, so the package says so and the
// folder reads as the author's (before: refused, suggesting an option the command lacks).
TEST_CASE("CourseCli_ReferencedDicomFolder_SkipsTheUnreadableFilesTheAuthorSkipped") {
  if (!test::requireSharedData("headsq DICOM") || !test::requireAppBinary("course packages")) return;
  test::TempDir dir("at-values");
  const fs::path ct = dir / "ct";
  copyHeadSeries(ct);
  std::ofstream(ct / "CTHead50b.dcm", std::ios::binary) << test::readFile(ct / "CTHead50.dcm").substr(0, 300);
  DatasetFiles files;
  files.volumePath = ct.string();
  files.skipUnreadableFiles = true;
  auto read = openDatasetFiles(files);
  REQUIRE_MESSAGE(read, test::errorText(read));
  FloatVolume labels(read->volume.geometry, 0.0f);
  for (std::size_t n = 0; n < labels.voxels.size(); ++n) labels.voxels[n] = read->volume.voxels[n] > 2000 ? 1.0f : 0.0f;
  const fs::path author = dir / "a.db", student = dir / "s.db", package = dir / "c.atcourse";
  authorCourse(dir.path(), ct, labels, "head", " --skip-unreadable", author);
  run("course export tour --out " + quoted(package) + " --reference-volume --db " + quoted(author));
  run("course import " + quoted(package) + " --volume " + quoted(ct) + " --db " + quoted(student));
  CHECK(valuesSeen("head", student) == valuesSeen("head", author));
  for (const auto& [db, png] : {std::pair{author, dir / "a.png"}, std::pair{student, dir / "s.png"}})
    run("slice head --axis z --index 40 --out " + quoted(png) + " --db " + quoted(db));
  CHECK(test::readFile(dir / "s.png") == test::readFile(dir / "a.png"));
}

// An MR (DICOM Modality MR) shared with its volume included: the package's int16 NRRD has no
// modality, so the package says it, and the student's dataset — and a package the student exports
// from it again — carries the note that its intensities are not attenuation (before: lost, and
// density-weighted distances on it came with no note).
TEST_CASE("CourseCli_IncludedMr_KeepsItsModalityAndTheNote") {
  if (!test::requireSharedData("headsq DICOM") || !test::requireAppBinary("course packages")) return;
  test::TempDir dir("at-values");
  const fs::path mr = dir / "mr";
  copyHeadSeries(mr, [](DcmDataset& d) { d.putAndInsertString(DCM_Modality, "MR"); });
  DatasetFiles files;
  files.volumePath = mr.string();
  auto read = openDatasetFiles(files);
  REQUIRE_MESSAGE(read, test::errorText(read));
  FloatVolume labels(read->volume.geometry, 0.0f);
  for (int k = 40; k < 50; ++k)
    for (int j = 28; j < 36; ++j)
      for (int i = 28; i < 36; ++i) labels.at(i, j, k) = 1.0f;
  const fs::path author = dir / "a.db", student = dir / "s.db", third = dir / "t.db";
  authorCourse(dir.path(), mr, labels, "mrhead", "", author);
  run("course export tour --out " + quoted(dir / "a.atcourse") + " --db " + quoted(author));
  run("course import " + quoted(dir / "a.atcourse") + " --db " + quoted(student));
  run("course export tour --out " + quoted(dir / "s.atcourse") + " --db " + quoted(student));
  run("course import " + quoted(dir / "s.atcourse") + " --db " + quoted(third));
  for (const fs::path& package : {dir / "a.atcourse", dir / "s.atcourse"}) {
    CAPTURE(package);
    auto entries = test::readTar(package);
    const auto manifest = nlohmann::json::parse(test::findEntry(entries, "manifest.json")->data);
    CHECK(manifest["format_version"] == 2);
    CHECK(manifest["dataset"]["reading"] == nlohmann::json{{"intensity", "auto"}, {"modality", "MR"}});
  }
  for (const fs::path& db : {author, student, third}) {
    CAPTURE(db);
    const nlohmann::json info = run("info mrhead --json --db " + quoted(db));
    CHECK(info["intensity"]["modality"] == "MR");
    CHECK(valuesSeen("mrhead", db) == valuesSeen("mrhead", author));
    const auto r = test::runApp("wdt mrhead block --backend cpu --json --db " + quoted(db));
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.err.find("'mrhead' is MR: its intensities are not attenuation") != std::string::npos);
  }
  // The desktop says it too, among its notes, on the student's machine.
  if (!test::requireXvfb()) return;
  test::DesktopOptions desktop;
  desktop.dataset = "mrhead";
  desktop.db = student;
  desktop.screenshot = (dir / "desktop.png").string();
  const test::DesktopRun shown = test::runDesktopScript(dir, {{"actions", {{{"do", "wait_field"}}}}}, desktop);
  REQUIRE_MESSAGE(shown.exitCode == 0, shown.err);
  CHECK(shown.err.find("'mrhead' is MR: its intensities are not attenuation, and density-weighted distances assume CT-like") !=
        std::string::npos);
}

TEST_CASE("DensityWeightsNote_OnlyWhereTheIntensitiesAreNotAttenuation") {
  Dataset d;
  d.id = "scan";
  for (const char* modality : {"", "CT", "OT"}) {
    d.intensity.modality = modality;
    CHECK_FALSE(app::densityWeightsNote(d));
  }
  d.intensity.modality = "MR";
  REQUIRE(app::densityWeightsNote(d));
  CHECK(app::densityWeightsNote(d)->rfind("'scan' is MR: its intensities are not attenuation", 0) == 0);
}

// A volume whose values a package cannot record (stored in int16 with a scale beyond ±1e12: a float
// export in other units than a scanner's): the included export is refused with one line that names
// the dataset and the way out, and writes no package; the referenced one still shares the course.
TEST_CASE("CourseCli_ValuesScaledBeyondAPackagesBounds_IncludedExportRefusedInOneLine") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir dir("at-values");
  writeScan(dir.path(), 1e15, 0, ScalarKind::Float32);  // up to 2.55e17
  const fs::path author = dir / "a.db", student = dir / "s.db", package = dir / "c.atcourse";
  run("import --volume " + quoted(dir / "scan.nrrd") + " --labels " + quoted(dir / "labels.nrrd") + " --names " +
      quoted(dir / "names.json") + " --name scan --db " + quoted(author));
  run("course new tour --dataset scan --db " + quoted(author));
  const std::string authorDb = test::readFile(author);
  const auto r = test::runApp("course export tour --out " + quoted(package) + " --db " + quoted(author));
  CHECK(r.exitCode != 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find("dataset 'scan'") != std::string::npos);
  CHECK(r.err.find("--reference-volume") != std::string::npos);
  CHECK_FALSE(fs::exists(package));
  CHECK(test::readFile(author) == authorDb);
  run("course export tour --reference-volume --out " + quoted(package) + " --db " + quoted(author));
  run("course import " + quoted(package) + " --volume " + quoted(dir / "scan.nrrd") + " --db " + quoted(student));
  CHECK(valuesSeen("scan", student) == valuesSeen("scan", author));
}

// An MR that came as a NRRD (its file records no modality), imported with --modality MR: the
// package carries the modality, included or referenced, and the student's dataset reads as the
// author's with the note.
TEST_CASE("CourseCli_MrGivenItsModalityAtImport_TravelsIncludedAndReferenced") {
  if (!test::requireAppBinary("course packages")) return;
  for (const char* exportOptions : {"", " --reference-volume"}) {
    CAPTURE(exportOptions);
    test::TempDir dir("at-values");
    writeScan(dir.path(), 12, 40, ScalarKind::UInt16);
    const Shared s = shareScan(dir, " --modality MR", exportOptions);
    checkSameValues(s);
    CHECK(s.formatVersion == 2);
    CHECK(s.reading.value("modality", "") == "MR");
    const nlohmann::json info = run("info scan --json --db " + quoted(dir / "s.db"));
    CHECK(info["intensity"]["modality"] == "MR");
    const auto r = test::runApp("wdt scan bone --backend cpu --json --db " + quoted(dir / "s.db"));
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.err.find("'scan' is MR: its intensities are not attenuation") != std::string::npos);
  }
}
