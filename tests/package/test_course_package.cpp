// Course packages: written and read back; every kind of altered package (a changed byte, a
// missing or unlisted entry, a newer format, names that escape, links, sizes past the limits)
// is refused with a message naming the package and the entry, and leaves nothing behind.
#include <doctest/doctest.h>

#include <fstream>
#include <random>

#include <nlohmann/json.hpp>

#include "core/sha256.h"
#include "lessons/course_json.h"
#include "package/course_package.h"
#include "tar_files.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/nrrd_io.h"

using namespace at;
using namespace at::package;
namespace fs = std::filesystem;

namespace {

const char* kCourse = R"({"schema": 1, "id": "mini_course", "title": "Mini", "dataset": "mini", "version": 3,
  "lessons": [{"id": "mini.one", "title": "One", "steps": [
    {"kind": "show", "structure": "cochlea", "preset": "mini_cochlea", "view": "superior", "title": "T", "text": "X"},
    {"kind": "question", "question": {"id": "mini.one.q", "kind": "name", "prompt": "Name it", "target": "cochlea"}}]}]})";

lessons::Course miniCourse() {
  auto c = lessons::parseCourseJson(kCourse, "mini");
  REQUIRE(c);
  return *c;
}

// A small dataset with the phantom's anatomy, called "mini".
const Dataset& miniDataset() {
  static const Dataset d = [] {
    Dataset copy = test::phantomOfSize(32);
    copy.id = "mini";
    return copy;
  }();
  return d;
}

// What an included-volume package of the mini dataset is written from (its data files in `dir`).
PackageInput includedInput(const test::TempDir& dir) {
  auto files = writeDatasetFiles(miniDataset(), dir.path(), true);
  REQUIRE_MESSAGE(files, test::errorText(files));
  PackageInput in;
  in.course = miniCourse();
  render::Preset preset;
  preset.name = "Mini cochlea";
  preset.t = 0.3f;
  in.presets.push_back({"mini_cochlea", preset, render::presetToJson(preset)});
  in.dataset.name = "mini";
  in.dataset.source = VolumeSource::Included;
  in.dataset.geometry = miniDataset().volume.geometry;
  in.dataset.sourceVolumeChecksum = "sha256:" + std::string(64, 'a');
  in.structures = miniDataset().structures;
  in.volumeFile = files->volume;
  in.labelsFile = files->labels;
  in.createdBy = "test";
  return in;
}

// An included-volume package of the mini dataset in `dir`.
fs::path writeIncluded(const test::TempDir& dir) {
  const fs::path out = dir / "mini.atcourse";
  auto ok = writePackage(out, includedInput(dir));
  REQUIRE_MESSAGE(ok, (ok ? "" : ok.error().message));
  return out;
}

// Reads `file` into `extract`; expects an error containing every one of `parts`, and nothing left in
// the extraction folder.
void expectRefused(const fs::path& file, std::initializer_list<const char*> parts, const ReadOptions& base = {}) {
  test::TempDir extract("at-extract");
  ReadOptions options = base;
  options.extractTo = extract.path();
  auto read = readPackageFile(file, options);
  REQUIRE_FALSE(read);
  for (const char* part : parts) CHECK_MESSAGE(read.error().message.find(part) != std::string::npos, read.error().message);
  CHECK(read.error().message.find('\n') == std::string::npos);
  CHECK(fs::is_empty(extract.path()));
}

// The package with `change` applied to its entries, as `name` in `dir`.
template <class Change>
fs::path altered(const test::TempDir& dir, const fs::path& original, const std::string& name, Change&& change) {
  auto entries = test::readTar(original);
  REQUIRE(entries.size() >= 5);
  change(entries);
  const fs::path out = dir / name;
  test::writeTar(out, entries);
  return out;
}

}  // namespace

TEST_CASE("CoursePackage_IncludedDataset_ReadsBackTheCourseePresetsStructuresAndIdenticalFiles") {
  test::TempDir dir;
  const fs::path file = writeIncluded(dir);
  test::TempDir extract("at-extract");
  ReadOptions options;
  options.extractTo = extract.path();
  auto read = readPackageFile(file, options);
  REQUIRE_MESSAGE(read, test::errorText(read));
  CHECK(lessons::courseToJson(read->course) == lessons::courseToJson(miniCourse()));
  CHECK(read->manifest.courseVersion == 3);
  CHECK((read->manifest.dataset.source == VolumeSource::Included));
  CHECK(read->manifest.dataset.geometry->sameGridAs(miniDataset().volume.geometry));
  REQUIRE(read->presets.size() == 1);
  CHECK(read->presets[0].id == "mini_cochlea");
  CHECK(read->presets[0].preset.t == doctest::Approx(0.3));
  CHECK(read->structures.size() == miniDataset().structures.size());
  CHECK(read->structures[0].id == miniDataset().structures[0].id);
  CHECK(read->structures[0].displayName == miniDataset().structures[0].displayName);
  REQUIRE(read->volumeFile == extract / "volume.nrrd");
  CHECK(test::readFile(read->volumeFile) == test::readFile(dir / "volume.nrrd"));
  CHECK(test::readFile(read->labelsFile) == test::readFile(dir / "labels.nrrd"));

  // The extracted files load as the same voxels.
  DatasetFiles files;
  files.volumePath = read->volumeFile.string();
  files.labelsPath = read->labelsFile.string();
  auto loaded = openDatasetFiles(files);
  REQUIRE_MESSAGE(loaded, test::errorText(loaded));
  CHECK(loaded->volume.voxels == miniDataset().volume.voxels);
  CHECK(loaded->labels.voxels == miniDataset().labels.voxels);

  // The same input gives the same bytes; reading from memory gives the same package.
  test::TempDir again;
  const fs::path second = writeIncluded(again);
  CHECK(test::readFile(second) == test::readFile(file));
  auto fromBytes = readPackageBytes(test::readFile(file), "in-memory");
  REQUIRE_MESSAGE(fromBytes, test::errorText(fromBytes));
  CHECK(fromBytes->volumeFile.empty());
  CHECK(fromBytes->hasLabels);
}

TEST_CASE("CoursePackage_BuiltinDataset_CarriesNoDatasetFiles") {
  test::TempDir dir;
  lessons::Course course = miniCourse();
  course.datasetId = "phantom";
  PackageInput in;
  in.course = course;
  in.dataset.name = "phantom";
  in.dataset.source = VolumeSource::Builtin;
  in.createdBy = "test";
  REQUIRE(writePackage(dir / "p.atcourse", in));
  auto read = readPackageFile(dir / "p.atcourse");
  REQUIRE_MESSAGE(read, test::errorText(read));
  CHECK(read->structures.empty());
  CHECK_FALSE(read->hasLabels);
  std::vector<std::string> names;
  for (const auto& e : test::readTar(dir / "p.atcourse")) names.push_back(e.name);
  CHECK(names == std::vector<std::string>{"manifest.json", "course.json"});

  // Structures for a built-in dataset are refused by the writer.
  in.structures = miniDataset().structures;
  CHECK_FALSE(writePackage(dir / "q.atcourse", in));
  CHECK_FALSE(fs::exists(dir / "q.atcourse"));
}

TEST_CASE("CoursePackage_AlteredPackages_AreRefusedWithOneLineNamingTheEntry") {
  test::TempDir dir;
  const fs::path file = writeIncluded(dir);

  SUBCASE("a changed volume byte") {
    expectRefused(altered(dir, file, "byte.atcourse",
                          [](auto& e) {
                            std::string& v = test::findEntry(e, "dataset/volume.nrrd")->data;
                            v[v.size() / 2] = char(v[v.size() / 2] ^ 0x01);
                          }),
                  {"byte.atcourse", "dataset/volume.nrrd", "checksum mismatch"});
  }
  SUBCASE("a changed course") {
    expectRefused(altered(dir, file, "course.atcourse",
                          [](auto& e) {
                            std::string& c = test::findEntry(e, "course.json")->data;
                            c.replace(c.find("Name it"), 7, "Name me");
                          }),
                  {"course.json", "checksum mismatch"});
  }
  SUBCASE("a missing file") {
    expectRefused(altered(dir, file, "missing.atcourse",
                          [](auto& e) { e.erase(e.begin() + long(e.size()) - 2); }),  // the labels
                  {"missing.atcourse", "dataset/labels.nrrd", "missing"});
    expectRefused(altered(dir, file, "novolume.atcourse", [](auto& e) { e.pop_back(); }),
                  {"dataset/volume.nrrd", "listed in the manifest but missing"});
  }
  SUBCASE("a newer format version") {
    auto newer = altered(dir, file, "newer.atcourse", [](auto& e) {
      auto m = nlohmann::json::parse(test::findEntry(e, "manifest.json")->data);
      m["format_version"] = kFormatVersion + 1;
      m["something_new"] = true;
      test::findEntry(e, "manifest.json")->data = m.dump();
    });
    expectRefused(newer, {("format version " + std::to_string(kFormatVersion + 1)).c_str(),
                          ("newer than this program reads (" + std::to_string(kFormatVersion) + ")").c_str()});
    auto read = readPackageFile(newer);
    REQUIRE_FALSE(read);
    CHECK((read.error().kind == ErrorKind::Unavailable));
  }
  SUBCASE("a hostile reading of the volume's values") {
    const std::vector<std::pair<nlohmann::json, std::string>> cases = {
        {{{"intensity", "kelvin"}}, "dataset.reading.intensity: must be auto, hu or plain, not 'kelvin'"},
        {{{"intercept", 5}}, "dataset.reading.intensity: missing"},
        {{{"intensity", "plain"}, {"slope", 0}}, "dataset.reading.slope: must be a number other than 0 within ±1e12"},
        {{{"intensity", "plain"}, {"slope", -1e300}}, "dataset.reading.slope: must be a number other than 0 within ±1e12"},
        {{{"intensity", "hu"}, {"intercept", 1e16}}, "dataset.reading.intercept: must be a number within ±1e15"},
        {{{"intensity", "hu"}, {"intercept", "-1024"}}, "dataset.reading.intercept: must be a finite number"},
        {{{"intensity", "hu"}, {"offset", 1}}, "dataset.reading.offset: unknown field"},
        {{{"intensity", "auto"}, {"skip_unreadable", "yes"}}, "dataset.reading.skip_unreadable: must be true or false"},
        {{{"intensity", "auto"}, {"modality", "mr"}}, "dataset.reading.modality: must be a DICOM modality code"},
        {{{"intensity", "auto"}, {"modality", "MR\n\x1b[2J"}}, "dataset.reading.modality: must be a DICOM modality code"},
        {{{"intensity", "auto"}, {"modality", std::string(17, 'M')}}, "dataset.reading.modality: must be a DICOM modality code"},
        {{{"intensity", "auto"}, {"modality", ""}}, "dataset.reading.modality: must not be empty"},
        {{{"intensity", "auto"}, {"modality", 5}}, "dataset.reading.modality: must be a string"},
        {nlohmann::json::array(), "dataset.reading: must be an object"}};
    for (const auto& [reading, message] : cases) {
      CAPTURE(reading.dump());
      expectRefused(altered(dir, file, "reading.atcourse",
                            [&](auto& e) {
                              auto m = nlohmann::json::parse(test::findEntry(e, "manifest.json")->data);
                              m["format_version"] = 2;
                              m["dataset"]["reading"] = reading;
                              test::findEntry(e, "manifest.json")->data = m.dump();
                            }),
                    {"reading.atcourse: manifest.json", message.c_str()});
    }
  }
  SUBCASE("a species no import gives") {
    for (const char* species : {"Dog", "dog\nskull", "dog\x1b[31m", "d o g"}) {
      CAPTURE(species);
      expectRefused(altered(dir, file, "species.atcourse",
                            [&](auto& e) {
                              auto m = nlohmann::json::parse(test::findEntry(e, "manifest.json")->data);
                              m["dataset"]["species"] = species;
                              test::findEntry(e, "manifest.json")->data = m.dump();
                            }),
                    {"manifest.json: dataset.species: ", "is not a species name"});
    }
  }
  SUBCASE("names that escape the package") {
    for (const char* name : {"../evil.json", "/tmp/evil.json", "presets/../../evil.json", "presets/./x.json", "a\\b.json",
                             "presets//x.json", ".hidden"}) {
      CAPTURE(name);
      expectRefused(altered(dir, file, "escape.atcourse",
                            [&](auto& e) { e.insert(e.begin() + 1, test::TarEntry{name, "{}"}); }),
                    {"escape.atcourse", "is refused"});
    }
    // Control characters in a name (found by fuzz_package): refused, and quoted as one printable line.
    for (const char* name : {"course.js\r", "presets/x\ny.json", "\x1b[31mred.json"}) {
      CAPTURE(name);
      const fs::path bad = altered(dir, file, "control.atcourse",
                                   [&](auto& e) { e.insert(e.begin() + 1, test::TarEntry{name, "{}"}); });
      expectRefused(bad, {"control.atcourse", "is refused"});
      auto read = readPackageFile(bad);
      REQUIRE_FALSE(read);
      for (char c : read.error().message) CHECK((static_cast<unsigned char>(c) >= 0x20 && c != 0x7f));
    }
    // … also when the manifest lists such a name.
    expectRefused(altered(dir, file, "listed.atcourse",
                          [](auto& e) {
                            auto m = nlohmann::json::parse(test::findEntry(e, "manifest.json")->data);
                            m["files"].push_back({{"path", "../evil.json"}, {"size", 2}, {"sha256", sha256Hex("{}")}});
                            test::findEntry(e, "manifest.json")->data = m.dump();
                          }),
                  {"manifest.json", "files[", "'../evil.json' is not a safe relative name"});
  }
  SUBCASE("links and other non-files") {
    expectRefused(altered(dir, file, "symlink.atcourse",
                          [](auto& e) {
                            test::TarEntry link{"presets/mini_cochlea.json", "", AE_IFLNK, "/etc/passwd"};
                            e.erase(e.begin() + 2);
                            e.insert(e.begin() + 2, link);
                          }),
                  {"presets/mini_cochlea.json", "is a link"});
    expectRefused(altered(dir, file, "hardlink.atcourse",
                          [](auto& e) {
                            test::TarEntry link{"presets/mini_cochlea.json"};
                            link.hardlink = "course.json";
                            e.erase(e.begin() + 2);
                            e.insert(e.begin() + 2, link);
                          }),
                  {"presets/mini_cochlea.json", "is a link"});
    expectRefused(altered(dir, file, "folder.atcourse",
                          [](auto& e) { e.insert(e.begin() + 1, test::TarEntry{"presets", "", AE_IFDIR}); }),
                  {"'presets/' is not a regular file"});
  }
  SUBCASE("unlisted, repeated and misplaced entries") {
    expectRefused(altered(dir, file, "extra.atcourse", [](auto& e) { e.push_back({"presets/extra.json", "{}"}); }),
                  {"'presets/extra.json' is not listed in the manifest"});
    expectRefused(altered(dir, file, "twice.atcourse", [](auto& e) { e.push_back(e[1]); }), {"appears twice"});
    expectRefused(altered(dir, file, "order.atcourse", [](auto& e) { std::swap(e[0], e[1]); }),
                  {"the first entry must be manifest.json"});
  }
  SUBCASE("a manifest that disagrees with the course") {
    expectRefused(altered(dir, file, "version.atcourse",
                          [](auto& e) {
                            auto m = nlohmann::json::parse(test::findEntry(e, "manifest.json")->data);
                            m["course"]["version"] = 4;
                            test::findEntry(e, "manifest.json")->data = m.dump();
                          }),
                  {"manifest.json: course", "version 4", "course.json is 'mini_course' version 3"});
  }
  SUBCASE("sizes beyond the limits") {
    ReadOptions small;
    small.limits.maxDataBytes = 1000;
    expectRefused(file, {"dataset/volume.nrrd", "more than the 1000"}, small);  // the labels compress to less
    ReadOptions few;
    few.limits.maxEntries = 3;
    expectRefused(file, {"more than 3 entries"}, few);
  }
  SUBCASE("a truncated package") {
    std::string bytes = test::readFile(file);
    const fs::path cut = dir / "cut.atcourse";
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() * 2 / 3);
    expectRefused(cut, {"cut.atcourse"});
  }
}

TEST_CASE("CoursePackage_GzipCompressedTar_IsReadToo") {
  test::TempDir dir;
  const fs::path file = writeIncluded(dir);
  test::writeTar(dir / "gz.atcourse", test::readTar(file), true);
  auto read = readPackageFile(dir / "gz.atcourse");
  REQUIRE_MESSAGE(read, test::errorText(read));
  CHECK(read->course.id == "mini_course");
}

TEST_CASE("CoursePackage_NotAPackage_IsAnErrorNotACrash") {
  for (const std::string& bytes : {std::string(), std::string("hello"), std::string(1024, '\0'), std::string(4096, 'x')}) {
    auto read = readPackageBytes(bytes, "junk");
    REQUIRE_FALSE(read);
    CHECK(read.error().message.rfind("junk: ", 0) == 0);
  }
  auto missing = readPackageFile("/nonexistent/x.atcourse");
  REQUIRE_FALSE(missing);
  CHECK((missing.error().kind == ErrorKind::NotFound));
  CHECK_FALSE(readPackageFile("/"));
}

TEST_CASE("SafeEntryName_AcceptsPlainRelativeNamesOnly") {
  for (const char* ok : {"course.json", "presets/a_b-c.1.json", "dataset/volume.nrrd"}) CHECK_MESSAGE(safeEntryName(ok), ok);
  for (const char* bad : {"", "/a", "../a", "a/../b", "a/./b", "./a", "a//b", "a/", ".a", "a\\b", "a b", "a:b", "é"})
    CHECK_MESSAGE(!safeEntryName(bad), bad);
  CHECK_FALSE(safeEntryName(std::string(201, 'a')));
}

TEST_CASE("Structures_RoundTripAndStrictErrorsNameTheEntry") {
  auto back = parseStructuresJson(structuresToJson(miniDataset().structures), "s.json");
  REQUIRE_MESSAGE(back, test::errorText(back));
  REQUIRE(back->size() == miniDataset().structures.size());
  CHECK((*back)[3].description == miniDataset().structures[3].description);
  const auto errorOf = [](const char* text) {
    auto r = parseStructuresJson(text, "s.json");
    return r ? std::string() : r.error().message;
  };
  CHECK(errorOf(R"([{"label": 0, "id": "a", "name": "A", "colour": [1,1,1]}])") == "s.json: [0].label: must be 1..65535");
  CHECK(errorOf(R"([{"label": 1, "id": "a", "name": "A", "colour": [1,1,1], "x": 1}])") == "s.json: [0].x: unknown field");
  CHECK(errorOf(R"([{"label": 1, "id": "a", "name": "A", "colour": [2,1,1]}])") == "s.json: [0].colour: must be 3 numbers in 0..1");
  CHECK(errorOf(R"([{"label": 1, "id": "a", "name": "A", "colour": [1,1,1]}, {"label": 1, "id": "b", "name": "B", "colour": [1,1,1]}])") ==
        "s.json: [1].label: label 1 is listed twice");
  CHECK(errorOf(R"([{"label": 1e999}])").find("not valid JSON") != std::string::npos);
}

// A package's structures never went through an importer: ids, names, systems and descriptions
// that no import gives (a line break that fakes a listing's next row, a terminal escape, a path)
// are refused, and the writer refuses to write them.
TEST_CASE("Structures_FromAPackage_HoldTheFormsAnImportGives") {
  const auto errorOf = [](const nlohmann::json& field) {
    nlohmann::json s = {{"label", 1}, {"id", "marrow"}, {"name", "Marrow"}, {"colour", {1, 1, 1}}, {"system", "bone"},
                        {"description", "Line one.\nLine two."}};
    s.update(field);
    auto r = parseStructuresJson(nlohmann::json::array({s}).dump(), "s.json");
    return r ? std::string() : r.error().message;
  };
  CHECK(errorOf(nlohmann::json::object()).empty());
  // The longest name an import gives: 120 characters of 4 bytes each and "…" (printableText).
  CHECK(errorOf({{"name", std::string(120 * 4, 'n') + "\u2026"}}).empty());
  CHECK(errorOf({{"name", "Schl\u00e4fenbein \u9acb"}}).empty());
  for (const char* id : {"Marrow", "../x", "a b", "a-b", "a.b", "", "\x1b[31m"}) {
    CAPTURE(id);
    CHECK(errorOf({{"id", id}}).find("s.json: [0].id: ") == 0);
  }
  CHECK(errorOf({{"id", std::string(101, 'a')}}).find("[0].id") != std::string::npos);
  for (const std::string& name : {std::string("Marrow\n    2  fake          Fake"), std::string("A\x1b]0;title\x07"),
                                  std::string("A\u202eB"), std::string(601, 'n')}) {
    CAPTURE(name);
    CHECK(errorOf({{"name", name}}) == "s.json: [0].name: must be one printable line of at most 600 bytes");
    CHECK(errorOf({{"system", name}}) == "s.json: [0].system: must be one printable line of at most 600 bytes");
  }
  CHECK(errorOf({{"description", "A\x1b[2J"}}).find("[0].description: must be printable text") != std::string::npos);
  CHECK(errorOf({{"description", std::string(4001, 'd')}}).find("[0].description") != std::string::npos);

  // The writer: a species or a structure the reader would refuse is not written.
  test::TempDir dir;
  const PackageInput in = includedInput(dir);
  PackageInput badName = in;
  badName.structures[0].displayName = "Two\nlines";
  auto refused = writePackage(dir / "bad.atcourse", badName);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("[0].name: must be one printable line") != std::string::npos);
  PackageInput badSpecies = in;
  badSpecies.dataset.species = "Dog";
  REQUIRE_FALSE(writePackage(dir / "bad.atcourse", badSpecies));
  CHECK_FALSE(fs::exists(dir / "bad.atcourse"));
  REQUIRE(writePackage(dir / "good.atcourse", in));
}

TEST_CASE("CoursePackage_RandomlyDamagedBytes_AreReadOrRefusedInOneLineNeverCrash") {
  test::TempDir dir;
  const std::string good = test::readFile(writeIncluded(dir));
  std::uint64_t state = test::freshSeed("CoursePackage_RandomlyDamagedBytes");
  const auto next = [&] {  // xorshift64*
    state ^= state >> 12;
    state ^= state << 25;
    state ^= state >> 27;
    return state * 2685821657736338717ull;
  };
  int refused = 0;
  for (int round = 0; round < 300; ++round) {
    std::string bytes = good;
    const int changes = 1 + int(next() % 4);
    for (int c = 0; c < changes; ++c) {
      // Mostly the headers and documents at the front, where the parser's decisions are.
      const std::size_t span = next() % 2 ? 4096 : bytes.size();
      bytes[next() % std::min(span, bytes.size())] = char(next());
    }
    if (next() % 8 == 0) bytes.resize(next() % bytes.size());
    auto read = readPackageBytes(bytes, "damaged");
    if (!read) {
      ++refused;
      CHECK(read.error().message.rfind("damaged: ", 0) == 0);
      CHECK(read.error().message.find('\n') == std::string::npos);
    }
  }
  CHECK(refused > 250);  // a changed byte inside a checksummed entry or header is noticed
}

// The reading a package records gives the dataset back: for any unit, rescale, value range and
// modality, the written volume.nrrd read with it has the dataset's unit, values and grey window and
// an MR stays an MR; where none is
// recorded, the file read by itself already does (so no package records a needless one).
TEST_CASE("CoursePackage_IncludedVolumeReading_GivesTheDatasetsUnitValuesAndWindowBack") {
  const std::uint64_t seed = test::freshSeed("CoursePackage_IncludedVolumeReading");
  std::mt19937_64 rng(seed);
  const auto pick = [&](auto&& list) { return list[std::uniform_int_distribution<std::size_t>(0, list.size() - 1)(rng)]; };
  int recorded = 0, trials = 0;
  for (; trials < 40; ++trials) {
    Dataset ds;
    ds.id = "values";
    Geometry g;
    g.dims = {7, 6, 5};
    g.spacingMm = {0.1, 0.1, 0.1};
    ds.volume = Volume(g);
    const int lo = pick(std::vector<int>{-32768, -3000, -1024, -499, 0, 100}), span = pick(std::vector<int>{10, 400, 3000, 60000});
    const int hi = std::min(32767, lo + span);
    for (std::int16_t& v : ds.volume.voxels) v = std::int16_t(std::uniform_int_distribution<int>(lo, hi)(rng));
    IntensityModel& m = ds.intensity;
    m.unit = pick(std::vector<IntensityUnit>{IntensityUnit::Hounsfield, IntensityUnit::Plain});
    if (!m.hounsfield()) {
      m.slope = pick(std::vector<double>{1, 1, 0.5, 3.75, 1.0 / 256});
      m.intercept = pick(std::vector<double>{0, 0, 33508, -1024, 12.5});
      m.window = histogramWindow(ds.volume.voxels);
    }
    m.modality = pick(std::vector<std::string>{"", "", "CT", "MR"});
    CAPTURE(trials);
    CAPTURE(m.modality);
    CAPTURE(lo);
    CAPTURE(hi);
    CAPTURE(m.hounsfield());
    CAPTURE(m.slope);
    CAPTURE(m.intercept);
    test::TempDir dir;
    auto files = writeDatasetFiles(ds, dir.path(), false);
    REQUIRE_MESSAGE(files, test::errorText(files));
    const std::optional<VolumeReading> reading = includedVolumeReading(ds);
    DatasetFiles open;
    open.volumePath = files->volume.string();
    if (reading) {
      ++recorded;
      open.intensity = reading->intensity;
      open.intercept = reading->intercept;
      open.slope = reading->slope;
      open.modality = reading->modality;
    }
    auto loaded = openDatasetFiles(open);
    REQUIRE_MESSAGE(loaded, test::errorText(loaded));
    CHECK(loaded->intensity.unit == m.unit);
    CHECK(loaded->intensity.attenuationLike() == m.attenuationLike());  // an MR's note is not lost
    CHECK(loaded->intensity.window == m.window);
    std::size_t differ = 0;
    for (std::size_t n = 0; n < ds.volume.voxels.size(); ++n)
      differ += loaded->intensity.valueOf(loaded->volume.voxels[n]) != m.valueOf(ds.volume.voxels[n]);
    CHECK(differ == 0);
  }
  MESSAGE(recorded << " of " << trials << " datasets needed a reading (seed " << seed << ")");
  CHECK(recorded > 0);
  CHECK(recorded < trials);
}
