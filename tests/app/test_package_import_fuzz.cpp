// Property fuzzing of course package import (not only parsing): random forgeries of a legitimate
// package — hostile dataset, course and preset names, padded and damaged documents, renamed,
// dropped and duplicated entries, readings of the volume's values at and past their bounds,
// structures no import gives, most with the checksums recomputed — are imported for real
// (importCoursePackage, as `course import` and the desktop's Open course… run it) into a scratch
// data folder. Properties, for every input:
//   * no file or folder outside the data folder is created, changed or removed;
//   * a refused import leaves the data folder and what the database holds (courses, datasets and
//     their structures, presets) exactly as they were;
//   * no staging folder outlives an import.
// The seed is printed; AT_IMPORT_FUZZ_RUNS sets the number of imports (default 40).
#include <doctest/doctest.h>

#include <cstdlib>
#include <random>

#include "course_import_fixtures.h"
#include "course_packages.h"
#include "data_paths.h"
#include "db/dataset_store.h"
#include "db/preset_store.h"
#include "learning_session.h"
#include "lessons/course_json.h"
#include "package_forgery.h"
#include "test_support.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

// What the database holds that an import may write, as text.
std::string storedContent(app::LearningSession& session) {
  std::string out;
  auto courses = session.curriculum().courses();
  REQUIRE(courses);
  for (const lessons::Course& c : *courses) out += lessons::courseToJson(c) + "\n";
  auto presets = db::listPresets(session.database());
  REQUIRE(presets);
  for (const db::StoredPreset& p : *presets) out += p.id + " " + p.json + "\n";
  auto datasets = db::listDatasets(session.database());
  REQUIRE(datasets);
  for (const db::DatasetRecord& d : *datasets) {
    out += d.name + " " + d.volumePath + " " + d.volumeChecksum + " " + d.labelsPath + "\n";
    auto structures = db::datasetStructures(session.database(), d.id);
    REQUIRE(structures);
    for (const Structure& s : *structures) out += "  " + s.id + " " + std::to_string(s.label) + "\n";
  }
  return out;
}

const std::vector<std::string> kNames = {"ear_lab", "other_lab", "..", ".", "../../victim", "../x", "a/b", "/tmp", "-rf",
                                         ".hidden", "datasets", "staging-x", "ear_l\xd0\xb0" "b", "cochlea_wdt", "x/../y", ""};

class Forger {
 public:
  Forger(std::vector<test::TarEntry> base, unsigned seed) : base_(std::move(base)), rng_(seed) {}

  std::vector<test::TarEntry> next() {
    auto entries = base_;
    auto manifest = nlohmann::json::parse(test::findEntry(entries, "manifest.json")->data);
    auto course = nlohmann::json::parse(test::findEntry(entries, "course.json")->data);
    const std::string courseId = "c" + std::to_string(counter_++);
    std::string text = course.dump();
    for (std::size_t at = 0; (at = text.find("ear_tour", at)) != std::string::npos; at += courseId.size()) text.replace(at, 8, courseId);
    course = nlohmann::json::parse(text);
    manifest["course"]["id"] = courseId;
    for (int changes = 1 + pick(3); changes > 0; --changes) {
      switch (pick(9)) {
        case 0: {  // the dataset's name
          const std::string name = kNames[std::size_t(pick(int(kNames.size())))];
          manifest["dataset"]["name"] = name;
          course["dataset"] = name;
          break;
        }
        case 1: {  // the course's id
          const std::string id = kNames[std::size_t(pick(int(kNames.size())))];
          manifest["course"]["id"] = id;
          course["id"] = id;
          break;
        }
        case 2: {  // a preset, maybe named like a shipped one or a path, maybe padded
          const std::string id = kNames[std::size_t(pick(int(kNames.size())))];
          entries.push_back(test::TarEntry("presets/" + id + ".json",
                                           std::string(std::size_t(pick(2) * 70000), ' ') + test::readFile(presetFile())));
          course["lessons"][0]["steps"][0]["preset"] = id;
          break;
        }
        case 3: {  // a damaged byte in one entry
          test::TarEntry& e = entries[std::size_t(1 + pick(int(entries.size()) - 1))];
          if (!e.data.empty()) e.data[std::size_t(pick(int(e.data.size())))] ^= char(1 + pick(255));
          break;
        }
        case 4: entries.erase(entries.begin() + 1 + pick(int(entries.size()) - 1)); break;
        case 5: entries.push_back(entries[std::size_t(1 + pick(int(entries.size()) - 1))]); break;
        case 6: entries[std::size_t(1 + pick(int(entries.size()) - 1))].name = kNames[std::size_t(pick(int(kNames.size())))]; break;
        case 7: {  // how the volume's values are read: any unit, rescales at and past their bounds
          nlohmann::json reading = {{"intensity", std::vector<std::string>{"auto", "hu", "plain", "kelvin"}[std::size_t(pick(4))]}};
          const std::vector<double> intercepts = {0, -1024, 32768, 1e15, -1e16, -3e38}, slopes = {1, 0.5, 1e-300, 1e12, -2e12, 0};
          if (pick(2)) reading["intercept"] = intercepts[std::size_t(pick(int(intercepts.size())))];
          if (pick(2)) reading["slope"] = slopes[std::size_t(pick(int(slopes.size())))];
          if (pick(2)) reading["skip_unreadable"] = pick(2) == 1;
          if (pick(2)) reading["modality"] = std::vector<std::string>{"MR", "CT", "mr", "", "MR\x1b[2J", std::string(17, 'P')}[std::size_t(pick(6))];
          manifest["format_version"] = 2;
          manifest["dataset"]["reading"] = reading;
          break;
        }
        case 8: {  // a structure's id, name or description as no import gives it
          if (test::TarEntry* st = test::findEntry(entries, "dataset/structures.json")) {
            auto structures = nlohmann::json::parse(st->data, nullptr, false);  // maybe damaged by an earlier change
            if (!structures.is_array()) break;
            const std::vector<std::string> texts = {"Ear\n    9  fake  Fake", "\x1b[2J", "a/b", "Cochlea", std::string(300, 'x'), "ok_id"};
            const char* field = std::vector<const char*>{"id", "name", "system", "description"}[std::size_t(pick(4))];
            if (!structures.empty()) structures[std::size_t(pick(int(structures.size())))][field] = texts[std::size_t(pick(int(texts.size())))];
            st->data = structures.dump();
          }
          break;
        }
      }
    }
    test::findEntry(entries, "manifest.json")->data = manifest.dump();
    if (test::TarEntry* c = test::findEntry(entries, "course.json")) c->data = course.dump();
    if (pick(5) != 0) test::rechecksum(entries);  // most forgeries pass every integrity check
    return entries;
  }

 private:
  int pick(int n) { return n <= 0 ? 0 : std::uniform_int_distribution<int>(0, n - 1)(rng_); }
  static fs::path presetFile() { return app::dataSubdirectory("presets") / "cochlea_bare.json"; }
  std::vector<test::TarEntry> base_;
  std::mt19937 rng_;
  int counter_ = 0;
};

}  // namespace

TEST_CASE("PackageImportFuzz_ForgedPackages_NeverTouchOutsideTheDataFolder_RefusalsChangeNothing") {
  if (!test::requireAppBinary("course packages")) return;
  // AT_IMPORT_FUZZ_SEED (older name) or AT_TEST_SEED replays a run.
  const unsigned seed = std::getenv("AT_IMPORT_FUZZ_SEED") ? unsigned(std::atol(std::getenv("AT_IMPORT_FUZZ_SEED")))
                                                             : unsigned(test::freshSeed("package import fuzz"));
  const int runs = std::getenv("AT_IMPORT_FUZZ_RUNS") ? std::atoi(std::getenv("AT_IMPORT_FUZZ_RUNS")) : 40;
  MESSAGE("package import fuzz: seed " << seed << " (AT_IMPORT_FUZZ_SEED), " << runs << " imports");
  INFO("seed " << seed);
  test::TempDir author("at-author"), home("at-home"), packages("at-packages");
  test::exportEarTour(author.path(), author / "ear.atcourse");
  const fs::path student = home / "student";
  fs::create_directories(home / "victim");
  std::ofstream(home / "victim" / "keep.txt") << "keep";
  fs::create_directories(student);
  auto session = app::LearningSession::open((student / "s.db").string());
  REQUIRE_MESSAGE(session, test::errorText(session));
  // The legitimate package first: later forgeries meet a stored course and dataset.
  app::CourseImportRequest first;
  first.package = author / "ear.atcourse";
  REQUIRE(app::importCoursePackage(**session, first));

  Forger forger(test::readTar(author / "ear.atcourse"), seed);
  const std::vector<std::string> skip = {"student/s.db"};
  int accepted = 0;
  for (int run = 0; run < runs; ++run) {
    CAPTURE(run);
    const fs::path file = packages / (std::to_string(run) + ".atcourse");
    test::writeTar(file, forger.next());
    const auto before = test::snapshotTree(home.path(), skip);
    const std::string stored = storedContent(**session);
    app::CourseImportRequest request;
    request.package = file;
    auto imported = app::importCoursePackage(**session, request);
    const auto after = test::snapshotTree(home.path(), skip);
    if (!imported) {
      CAPTURE(imported.error().message);
      CHECK(after == before);
      CHECK(storedContent(**session) == stored);
    } else {
      ++accepted;
      for (const auto& [path, content] : after)
        if (path.rfind("student/s-data/", 0) != 0) CHECK_MESSAGE((before.count(path) && before.at(path) == content), path);
      for (const auto& [path, content] : before)
        if (path.rfind("student/s-data/", 0) != 0) CHECK_MESSAGE(after.count(path), path);
    }
    for (const auto& [path, content] : after) CHECK_MESSAGE(path.rfind("student/s-data/staging-", 0) != 0, path);
  }
  MESSAGE("package import fuzz: " << accepted << " of " << runs << " forgeries imported");
}
