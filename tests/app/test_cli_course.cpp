// `anatomy-tutor course`: a course authored through the CLI on an imported dataset travels as a
// package to a fresh database in another folder, under another user, and plays to the end with
// the author's files and the package gone; tampered, conflicting and incomplete packages are
// refused with one line and change nothing.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <optional>

#include <nlohmann/json.hpp>

#include "../package/tar_files.h"
#include "cli_checks.h"
#include "lab_machine.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "test_databases.h"
#include "test_support.h"
#include "package/course_package.h"
#include "render/scene.h"
#include "volume/png_image.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// The 32³ phantom as an imported dataset "ear_lab" in `db` (files in `dir`, names by label).
void importPhantom(const fs::path& dir, const fs::path& db, const std::string& name = "ear_lab", int size = 32) {
  const Dataset& phantom = test::phantomOfSize(size);
  auto files = package::writeDatasetFiles(phantom, dir, true);
  REQUIRE_MESSAGE(files, test::errorText(files));
  nlohmann::json names = nlohmann::json::object();
  for (const Structure& s : phantom.structures) names[std::to_string(s.label)] = s.displayName;
  std::ofstream(dir / "names.json") << names.dump();
  auto r = test::runApp("import --volume " + quoted(dir / "volume.nrrd") + " --labels " + quoted(dir / "labels.nrrd") +
                        " --names " + quoted(dir / "names.json") + " --name " + name + " --db " + quoted(db));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
}

// One typed answer per question of `courseFile`'s first lesson: the target's name as the course names it.
std::string nameAnswers(const fs::path& courseFile) {
  const auto course = nlohmann::json::parse(test::readFile(courseFile));
  std::string lines;
  for (const auto& step : course["lessons"][0]["steps"])
    if (step["kind"] == "question") lines += nlohmann::json{{"text", step["question"]["target"]}}.dump() + "\n";
  return lines;
}

std::string courseList(const fs::path& db) {
  auto r = test::runApp("course list --db " + quoted(db));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  return r.out;
}

// The author's course "ear_tour" (version 2, edited as JSON) exported from `author` to `package`.
void authorAndExport(const test::TempDir& author, const fs::path& package, const std::string& exportOptions = "") {
  const fs::path db = author / "a.db";
  importPhantom(author.path(), db);
  auto made = test::runApp("course new ear_tour --dataset ear_lab --title 'Ear tour' --out " + quoted(author / "ear_tour.json") +
                           " --db " + quoted(db));
  REQUIRE_MESSAGE(made.exitCode == 0, made.err);
  CHECK(made.out.find("course 'ear_tour' (Ear tour) on 'ear_lab'") != std::string::npos);
  CHECK(made.out.find("not stored") != std::string::npos);
  CHECK(courseList(db).find("ear_tour") == std::string::npos);  // a draft until imported
  // The author edits the file (version unchanged) and imports it: added, no version to raise.
  auto course = nlohmann::json::parse(test::readFile(author / "ear_tour.json"));
  course["lessons"][0]["steps"][0]["text"] = "Draft edit.";
  std::ofstream(author / "ear_tour.json") << course.dump(2);
  auto first = test::runApp("course import " + quoted(author / "ear_tour.json") + " --db " + quoted(db));
  REQUIRE_MESSAGE(first.exitCode == 0, first.err);
  CHECK(first.out == "course 'ear_tour' version 1: added\n");
  // A later edit: a better first text, version 2.
  course["version"] = 2;
  course["lessons"][0]["steps"][0]["text"] = "Edited by the author.";
  std::ofstream(author / "ear_tour.json") << course.dump(2);
  auto valid = test::runApp("course validate " + quoted(author / "ear_tour.json") + " --db " + quoted(db));
  REQUIRE_MESSAGE(valid.exitCode == 0, valid.err);
  CHECK(valid.out.find("structures checked against dataset 'ear_lab'") != std::string::npos);
  auto stored = test::runApp("course import " + quoted(author / "ear_tour.json") + " --db " + quoted(db));
  REQUIRE_MESSAGE(stored.exitCode == 0, stored.err);
  CHECK(stored.out == "course 'ear_tour' version 2: updated\n");
  auto exported = test::runApp("course export ear_tour --out " + quoted(package) + " --db " + quoted(db) + exportOptions);
  REQUIRE_MESSAGE(exported.exitCode == 0, exported.err);
}

}  // namespace

TEST_CASE("CourseCli_AuthoredCourse_TravelsAsAPackageToAnotherDatabaseAndPlaysToTheEnd") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  authorAndExport(author, author / "ear.atcourse");
  // The package moves to the student's folder; the author's files disappear.
  fs::rename(author / "ear.atcourse", student / "ear.atcourse");
  for (const char* f : {"volume.nrrd", "labels.nrrd", "names.json", "a.db"}) fs::remove(author / f);

  fs::create_directories(student / "class1");
  const fs::path first = student / "class1" / "s.db";
  auto imported = test::runApp("course import " + quoted(student / "ear.atcourse") + " --db " + quoted(first));
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  CHECK(imported.out.find("course 'ear_tour' (Ear tour) version 2: added") != std::string::npos);
  CHECK(imported.out.find("dataset 'ear_lab': imported into " + (student / "class1" / "s-data" / "datasets" / "ear_lab").string()) !=
        std::string::npos);
  fs::remove(student / "ear.atcourse");
  // The database and its data folder move together: the dataset's paths are kept relative to it.
  fs::rename(student / "class1", student / "class2");
  const fs::path db = student / "class2" / "s.db";
  {
    auto database = db::openDatabase(db.string());
    REQUIRE(database);
    auto record = db::findDataset(*database, "ear_lab");
    REQUIRE(record);
    REQUIRE(*record);
    CHECK((*record)->volumePath == (student / "class2" / "s-data" / "datasets" / "ear_lab" / "volume.nrrd").string());
    CHECK((*record)->labelsPath == (student / "class2" / "s-data" / "datasets" / "ear_lab" / "labels.nrrd").string());
    CHECK((*record)->structureCount == int(test::phantomOfSize(32).structures.size()));
  }
  std::ofstream(student / "answers.jsonl") << nameAnswers(author / "ear_tour.json");
  auto played = test::runApp("play ear_tour.tour --user dana --new-user --no-views --answers " + quoted(student / "answers.jsonl") +
                             " --db " + quoted(db));
  REQUIRE_MESSAGE(played.exitCode == 0, played.err);
  CHECK(played.out.find("Edited by the author.") != std::string::npos);
  const std::size_t questions = test::phantomOfSize(32).structures.size();
  CHECK(played.out.find("Lesson finished: " + std::to_string(questions) + " of " + std::to_string(questions) + " questions right") !=
        std::string::npos);
}

TEST_CASE("CourseCli_TamperedOrConflictingPackages_AreRefusedWithOneLineAndChangeNothing") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  const fs::path package = author / "ear.atcourse";
  authorAndExport(author, package);
  const fs::path db = student / "s.db";
  const std::string before = courseList(db);
  const auto tampered = [&](const std::string& name, auto change) {
    auto entries = test::readTar(package);
    change(entries);
    test::writeTar(student / name, entries);
    return student / name;
  };
  const auto refused = [&](const fs::path& file, const std::string& mention, const std::string& extra = "") {
    auto r = test::runApp("course import " + quoted(file) + " --db " + quoted(db) + extra);
    test::checkOneLineError(r, mention);
    CHECK(courseList(db) == before);
    CHECK(test::importedDatasetNames(db).empty());
    std::error_code ec;
    CHECK((!fs::exists(student / "s-data" / "datasets", ec) || fs::is_empty(student / "s-data" / "datasets")));
    return r.err;
  };

  SUBCASE("a changed volume byte") {
    refused(tampered("byte.atcourse",
                     [](auto& e) {
                       std::string& v = test::findEntry(e, "dataset/volume.nrrd")->data;
                       v[v.size() - 10] = char(v[v.size() - 10] ^ 0x20);
                     }),
            "dataset/volume.nrrd: checksum mismatch");
  }
  SUBCASE("a missing file") {
    refused(tampered("missing.atcourse", [](auto& e) { e.pop_back(); }),
            "dataset/volume.nrrd is listed in the manifest but missing from the package");
  }
  SUBCASE("a newer format version") {
    refused(tampered("newer.atcourse",
                     [](auto& e) {
                       auto m = nlohmann::json::parse(test::findEntry(e, "manifest.json")->data);
                       m["format_version"] = package::kFormatVersion + 1;
                       test::findEntry(e, "manifest.json")->data = m.dump();
                     }),
            "format version " + std::to_string(package::kFormatVersion + 1));
  }
  SUBCASE("an older version, or other content under the same version, of a stored course") {
    auto first = test::runApp("course import " + quoted(package) + " --db " + quoted(db));
    REQUIRE_MESSAGE(first.exitCode == 0, first.err);
    const std::string stored = courseList(db);
    auto course = nlohmann::json::parse(test::readFile(author / "ear_tour.json"));
    course["version"] = 1;
    std::ofstream(author / "older.json") << course.dump();
    auto older = test::runApp("course import " + quoted(author / "older.json") + " --db " + quoted(db));
    test::checkOneLineError(older, "version 2 is stored, newer than this one's version 1");
    course["version"] = 2;
    course["title"] = "Another ear tour";
    std::ofstream(author / "other.json") << course.dump();
    auto other = test::runApp("course import " + quoted(author / "other.json") + " --db " + quoted(db));
    test::checkOneLineError(other, "is stored with other content");
    CHECK(courseList(db) == stored);
    auto again = test::runApp("course import " + quoted(package) + " --db " + quoted(db));
    CHECK(again.exitCode == 0);
    CHECK(again.out.find("version 2: unchanged") != std::string::npos);
    CHECK(again.out.find("dataset 'ear_lab': already present") != std::string::npos);
  }
  SUBCASE("a dataset name already imported with another volume") {
    test::TempDir other("at-other");
    importPhantom(other.path(), db, "ear_lab", 24);
    auto r = test::runApp("course import " + quoted(package) + " --db " + quoted(db));
    test::checkOneLineError(r, "a dataset named 'ear_lab' is already imported with another volume");
    CHECK(courseList(db) == before);
  }
}

TEST_CASE("CourseCli_ReferencedVolume_IsAskedForAndCheckedByItsChecksum") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  const fs::path package = author / "ref.atcourse";
  authorAndExport(author, package, " --reference-volume --note 'ask the anatomy office'");
  std::vector<std::string> names;
  for (const auto& e : test::readTar(package)) names.push_back(e.name);
  CHECK(std::find(names.begin(), names.end(), "dataset/volume.nrrd") == names.end());
  const fs::path db = student / "s.db";

  auto without = test::runApp("course import " + quoted(package) + " --db " + quoted(db));
  test::checkOneLineError(without, "give the scan with --volume PATH (volume.nrrd, sha256:");
  CHECK(without.err.find("ask the anatomy office") != std::string::npos);
  auto wrong = test::runApp("course import " + quoted(package) + " --volume " + quoted(author / "labels.nrrd") + " --db " + quoted(db));
  test::checkOneLineError(wrong, "is not the course's volume: expected volume.nrrd, sha256:");
  CHECK(test::importedDatasetNames(db).empty());

  auto right = test::runApp("course import " + quoted(package) + " --volume " + quoted(author / "volume.nrrd") + " --db " + quoted(db));
  REQUIRE_MESSAGE(right.exitCode == 0, right.err);
  CHECK(fs::is_regular_file(student / "s-data" / "datasets" / "ear_lab" / "volume.nrrd"));
  CHECK(test::importedDatasetNames(db) == std::vector<std::string>{"ear_lab"});
}

namespace {

using test::OnMachine;

// The files under `dir`, relative to it.
std::vector<std::string> filesUnder(const fs::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out.push_back(fs::relative(e.path(), dir).string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("CourseCli_PackageOnAClassServer_RowsOnceFilesOnEachLabMachineThatImportsIt") {
  if (!test::requireAppBinary("course packages")) return;
  auto url = test::freshPostgresDatabase("the class-server course import test");
  if (!url) return;
  test::TempDir author("at-author"), labA("at-lab-a"), labB("at-lab-b");
  const fs::path package = author / "ear.atcourse";
  authorAndExport(author, package);
  // The same course under version 2 with other content, packaged by another author's database.
  test::TempDir author2("at-author2");
  importPhantom(author2.path(), author2 / "b.db");
  auto edited = nlohmann::json::parse(test::readFile(author / "ear_tour.json"));
  edited["title"] = "Another ear tour";
  std::ofstream(author2 / "other.json") << edited.dump();
  REQUIRE(test::runApp("course import " + quoted(author2 / "other.json") + " --db " + quoted(author2 / "b.db")).exitCode == 0);
  REQUIRE(test::runApp("course export ear_tour --out " + quoted(author2 / "other.atcourse") + " --db " +
                       quoted(author2 / "b.db")).exitCode == 0);
  std::ofstream(labA / "answers.jsonl") << nameAnswers(author / "ear_tour.json");
  const std::string server = " --db '" + *url + "'";
  const std::string play = "play ear_tour.tour --user dana --new-user --no-views --answers " + quoted(labA / "answers.jsonl") + server;
  const std::size_t questions = test::phantomOfSize(32).structures.size();
  const std::string finished =
      "Lesson finished: " + std::to_string(questions) + " of " + std::to_string(questions) + " questions right";

  fs::path folderA;
  {
    OnMachine machine(labA.path());
    auto imported = test::runApp("course import " + quoted(package) + server);
    REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
    CHECK(imported.out.find("course 'ear_tour' (Ear tour) version 2: added") != std::string::npos);
    CHECK(imported.out.find("dataset 'ear_lab': imported into " + (labA / "anatomy-tutor" / "servers").string()) != std::string::npos);
    const auto servers = filesUnder(labA / "anatomy-tutor" / "servers");
    REQUIRE(servers.size() == 2);  // one folder for this server: the dataset's volume and label map
    folderA = labA / "anatomy-tutor" / "servers" / fs::path(servers[0]).begin()->string();
    CHECK(filesUnder(folderA) == std::vector<std::string>{"datasets/ear_lab/labels.nrrd", "datasets/ear_lab/volume.nrrd"});
    auto played = test::runApp(play);
    REQUIRE_MESSAGE(played.exitCode == 0, played.err);
    CHECK(played.out.find(finished) != std::string::npos);
  }
  {
    OnMachine machine(labB.path());
    // Before its import, machine B has the course's rows (from the server) but not the scan its
    // pictures are drawn from.
    const std::string playWithViews = "play ear_tour.tour --user erin --new-user --views " + quoted(labB / "views") +
                                      " --answers " + quoted(labA / "answers.jsonl") + server;
    auto early = test::runApp(playWithViews);
    CAPTURE(early.err);
    REQUIRE(early.exitCode == 0);  // the lesson's text and name questions go on without pictures
    CHECK(early.out.find("(no pictures: dataset 'ear_lab': its volume cannot be read: " +
                         (labB / "anatomy-tutor" / "servers").string()) != std::string::npos);
    CHECK(filesUnder(labB / "views").empty());
    // Other content under the stored version: refused as on SQLite, no file placed.
    auto other = test::runApp("course import " + quoted(author2 / "other.atcourse") + server);
    test::checkOneLineError(other, "is stored with other content");
    CHECK(filesUnder(labB / "anatomy-tutor").empty());

    auto imported = test::runApp("course import " + quoted(package) + server);
    REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
    CHECK(imported.out.find("version 2: unchanged") != std::string::npos);
    const fs::path folderB = labB / "anatomy-tutor" / "servers" / folderA.filename();
    CHECK(imported.out.find("dataset 'ear_lab': on the server already; its files placed on this machine into " +
                            (folderB / "datasets" / "ear_lab").string()) != std::string::npos);
    CHECK(filesUnder(folderB) == filesUnder(folderA));
    CHECK(test::readFile(folderB / "datasets/ear_lab/volume.nrrd") == test::readFile(folderA / "datasets/ear_lab/volume.nrrd"));
    auto played = test::runApp(playWithViews);
    REQUIRE_MESSAGE(played.exitCode == 0, played.err);
    CHECK(played.out.find(finished) != std::string::npos);
    CHECK(played.out.find("no pictures") == std::string::npos);
    CHECK(filesUnder(labB / "views").size() == 32);  // every step's picture, drawn from this machine's copy of the scan
    if (const char* keep = std::getenv("AT_KEEP_SCREENSHOTS"))
      for (const auto& f : filesUnder(labB / "views"))
        fs::copy_file(labB / "views" / f, fs::path(keep) / ("server_course_" + fs::path(f).filename().string()),
                      fs::copy_options::overwrite_existing);
    auto again = test::runApp("course import " + quoted(package) + server);
    REQUIRE_MESSAGE(again.exitCode == 0, again.err);
    CHECK(again.out.find("version 2: unchanged") != std::string::npos);
    CHECK(again.out.find("dataset 'ear_lab': already present") != std::string::npos);
  }
  // The server holds the course and its dataset once, whatever the number of machines.
  CHECK(test::postgresValue(*url, "SELECT COUNT(*) FROM courses WHERE id = 'ear_tour'") == "1");
  CHECK(test::postgresValue(*url, "SELECT COUNT(*) FROM datasets WHERE name = 'ear_lab'") == "1");
  CHECK(test::postgresValue(*url, "SELECT volume_path FROM datasets WHERE name = 'ear_lab'") == "datasets/ear_lab/volume.nrrd");
  CHECK(test::postgresValue(*url, "SELECT title FROM courses WHERE id = 'ear_tour'") == "Ear tour");
}

TEST_CASE("CourseCli_Validate_NamesTheFieldOfAStructureTheDatasetLacks") {
  if (!test::requireAppBinary("course validate")) return;
  test::TempDir dir;
  auto course = nlohmann::json::parse(test::readFile(test::sourceDir() / "data" / "courses" / "temporal_bone.json"));
  course["lessons"][0]["steps"][0]["structure"] = "pancreas";
  std::ofstream(dir / "bad.json") << course.dump();
  auto r = test::runApp("course validate " + quoted(dir / "bad.json") + " --db " + quoted(dir / "v.db"));
  test::checkOneLineError(r, "bad.json: lessons[0].steps[0].structure: no structure 'pancreas' in dataset 'phantom'");
  course["lessons"][0]["steps"][0]["kind"] = "lecture";
  std::ofstream(dir / "bad.json") << course.dump();
  test::checkOneLineError(test::runApp("course validate " + quoted(dir / "bad.json")), "lessons[0].steps[0].kind");
  auto good = test::runApp("course validate " + quoted(test::sourceDir() / "data" / "courses" / "temporal_bone.json"));
  CHECK_MESSAGE(good.exitCode == 0, good.err);
  CHECK(good.out.find("valid: course 'temporal_bone'") != std::string::npos);
}

// A locate question asked in a view that draws nothing but the highlighted region (the bare
// preset): the cochlea's label lies behind the blackness, so a click there would pick it, but no
// student can see where that is. `course validate` refuses the file and names the question.
TEST_CASE("CourseCli_Validate_RefusesALocateQuestionWhoseViewDrawsNothingWhereItsTargetIs") {
  if (!test::requireAppBinary("course validate")) return;
  test::TempDir dir;
  auto course = nlohmann::json::parse(test::readFile(test::sourceDir() / "data" / "courses" / "temporal_bone.json"));
  nlohmann::json& steps = course["lessons"][0]["steps"];
  std::size_t at = 0;
  while (at < steps.size() && !(steps[at].contains("question") && steps[at]["question"]["kind"] == "locate")) ++at;
  REQUIRE(at < steps.size());
  steps[at]["preset"] = "vestibule_bare";
  std::ofstream(dir / "blank.json") << course.dump(2);
  const std::string before = test::readFile(dir / "blank.json");
  auto r = test::runApp("course validate " + quoted(dir / "blank.json") + " --db " + quoted(dir / "v.db"));
  CHECK(r.exitCode != 0);
  const std::string path = "lessons[0].steps[" + std::to_string(at) + "].question";
  CHECK_MESSAGE(r.err.find(path + " (" + steps[at]["question"]["id"].get<std::string>() + "): not answerable: the " +
                           steps[at]["question"]["target"].get<std::string>() + " is not drawn in its view") !=
                    std::string::npos,
                r.err);
  CHECK(r.err.find("1 of 6 locate questions cannot be answered in their views") != std::string::npos);
  CHECK(test::readFile(dir / "blank.json") == before);
}

// A step's free camera and clipping plane (course JSON "camera", "clip"): checked by `course
// validate` with the field's path, stored by `course import`, and what `play` draws.
TEST_CASE("CourseCli_StepCameraAndClip_AreValidatedStoredAndDrawnByPlay") {
  if (!test::requireAppBinary("course validate")) return;
  test::TempDir dir;
  const fs::path db = dir / "p.db";
  const Dataset& phantom = test::phantomOfSize(128);  // "phantom" as play opens it
  const Structure* cochlea = phantom.findStructure("cochlea");
  REQUIRE(cochlea);
  auto frame = render::structureFrame(phantom.labels, cochlea->label);
  REQUIRE(frame);
  const Vec3 c = frame->centroidMm;
  const nlohmann::json show = {{"kind", "show"}, {"structure", "cochlea"}, {"preset", "cochlea_wdt"}, {"view", "superior"},
                               {"title", "The cochlea"}, {"text", "Coiled."}};
  nlohmann::json placed = show;
  // From the patient's front, a little from the left and below, close; the part in front of the
  // cochlea's centre cut away.
  placed["camera"] = {{"target_mm", c}, {"look", {-0.3, 1, 0.2}}, {"up", {0, 0, 1}}, {"distance_mm", 25}};
  placed["clip"] = {0, -1, 0, -c[1]};
  const nlohmann::json course = {
      {"schema", 1}, {"id", "placed"}, {"title", "Placed"}, {"dataset", "phantom"},
      {"lessons", {{{"id", "placed.free"}, {"title", "Free"}, {"steps", {placed}}},
                   {{"id", "placed.named"}, {"title", "Named"}, {"steps", {show}}}}}};
  std::ofstream(dir / "placed.json") << course.dump(2);
  auto valid = test::runApp("course validate " + quoted(dir / "placed.json") + " --db " + quoted(db));
  CHECK_MESSAGE(valid.exitCode == 0, valid.err);

  nlohmann::json bad = course;
  bad["lessons"][0]["steps"][0]["clip"] = {0.5, -1, 0, 2};
  std::ofstream(dir / "bad.json") << bad.dump();
  test::checkOneLineError(test::runApp("course validate " + quoted(dir / "bad.json")),
                          "bad.json: lessons[0].steps[0].clip: the normal must lie along one patient axis");
  bad = course;
  bad["lessons"][0]["steps"][0]["camera"]["up"] = {0, 2, 0};
  bad["lessons"][0]["steps"][0]["camera"]["look"] = {0, -1, 0};
  std::ofstream(dir / "bad.json") << bad.dump();
  test::checkOneLineError(test::runApp("course validate " + quoted(dir / "bad.json")),
                          "bad.json: lessons[0].steps[0].camera.up: must not be zero or along 'look'");

  auto imported = test::runApp("course import " + quoted(dir / "placed.json") + " --db " + quoted(db));
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  for (const char* lesson : {"placed.free", "placed.named"}) {
    auto played = test::runApp(std::string("play ") + lesson + " --user pat --views " + quoted(dir / lesson) + " --db " +
                               quoted(db) + (std::string(lesson) == "placed.free" ? " --new-user" : ""));
    REQUIRE_MESSAGE(played.exitCode == 0, played.err);
  }
  auto free = readPng((dir / "placed.free" / "placed.free-01.png").string());
  auto named = readPng((dir / "placed.named" / "placed.named-01.png").string());
  REQUIRE(free);
  REQUIRE(named);
  REQUIRE(free->width == named->width);
  REQUIRE(free->height == named->height);
  // The free camera is close (25 mm) and the front is cut away: not the framed superior view.
  double diff = 0;
  for (int y = 0; y < free->height; ++y)
    for (int x = 0; x < free->width; ++x)
      for (int ch = 0; ch < 3; ++ch) diff += std::abs(int(free->pixel(x, y)[ch]) - int(named->pixel(x, y)[ch]));
  diff /= double(free->width) * free->height * 3;
  MESSAGE("mean absolute difference free camera vs named view: " << diff);
  CHECK(diff > 8);
}
