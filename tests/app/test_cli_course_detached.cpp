// A course package that references its scan, where the scan is a detached NRRD header with one
// data file per slice (as µCT exports often are): the student gives the header, and the import
// copies it with every data file into the dataset's folder, so that the dataset opens with the
// author's values when the student's own copy has gone. Hostile headers: a data file named like
// the package's label map lands beside the header, never on the label map; a data file named by an
// absolute path cannot travel and the import is refused with one line, leaving the student's files
// as they were; nothing is ever written outside the student's data folder.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <vector>

#include <nlohmann/json.hpp>

#include "../package/tar_files.h"
#include "cli_checks.h"
#include "lab_machine.h"
#include "test_databases.h"
#include "db/checksum.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/nrrd_io.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// Every regular file under `dir` with its bytes (paths relative to `dir`).
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> out;
  std::error_code ec;
  if (!fs::exists(dir, ec)) return out;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) out[fs::relative(e.path(), dir).string()] = test::readFile(e.path());
  return out;
}

// The 32³ phantom as a detached header `header` in `dir` with one raw int16 slice per data file
// (`sliceName(k)`, relative to `dir` or absolute), its label map in dir/seg and label names.
void writeDetached(const fs::path& dir, const std::string& header, const std::function<std::string(int)>& sliceName) {
  const Dataset& phantom = test::phantomOfSize(32);
  Geometry g = phantom.volume.geometry;
  g.originMm = {0, 0, 0};
  g.direction = Mat3::identity();
  const Dims d = g.dims;
  std::ofstream h(dir / header, std::ios::binary);
  h << "NRRD0004\ntype: short\ndimension: 3\nsizes: " << d.x << " " << d.y << " " << d.z
    << "\nspace: left-posterior-superior\nspace directions: (" << g.spacingMm[0] << ",0,0) (0," << g.spacingMm[1] << ",0) (0,0,"
    << g.spacingMm[2] << ")\nspace origin: (0,0,0)\nendian: little\nencoding: raw\ndata file: LIST\n";
  for (int k = 0; k < d.z; ++k) {
    const std::string name = sliceName(k);
    h << name << "\n";
    const fs::path path = fs::path(name).is_absolute() ? fs::path(name) : dir / name;
    fs::create_directories(path.parent_path());
    std::ofstream slice(path, std::ios::binary);
    slice.write(reinterpret_cast<const char*>(phantom.volume.voxels.data() + std::size_t(k) * d.x * d.y),
                std::streamsize(std::size_t(d.x) * d.y * sizeof(std::int16_t)));
  }
  h.close();
  FloatVolume labels(g);
  labels.voxels.assign(phantom.labels.voxels.begin(), phantom.labels.voxels.end());
  fs::create_directories(dir / "seg");
  REQUIRE(writeNrrd((dir / "seg" / "labels.nrrd").string(), labels, ScalarKind::UInt16));
  nlohmann::json names = nlohmann::json::object();
  for (const Structure& s : phantom.structures) names[std::to_string(s.label)] = s.displayName;
  std::ofstream(dir / "seg" / "names.json") << names.dump();
}

test::CommandResult runIn(const std::string& args) { return test::runApp(args); }

// Imports `header` as dataset "ear_slices" (read with --slope 2: a rescale the package must
// carry), makes a course on it and exports it referencing the scan.
fs::path authorReferencedCourse(const fs::path& dir, const std::string& header) {
  const fs::path db = dir / "a.db", package = dir / "ear.atcourse";
  for (const std::string& args :
       {"import --volume " + quoted(dir / header) + " --labels " + quoted(dir / "seg" / "labels.nrrd") + " --names " +
            quoted(dir / "seg" / "names.json") + " --name ear_slices --slope 2 --db " + quoted(db),
        "course new tour --dataset ear_slices --db " + quoted(db),
        "course export tour --out " + quoted(package) + " --reference-volume --note 'the lab share' --db " + quoted(db)}) {
    auto r = runIn(args);
    REQUIRE_MESSAGE(r.exitCode == 0, args << ": " << r.err);
  }
  return package;
}

std::string slicePng(const fs::path& db, const fs::path& out) {
  auto r = runIn("slice ear_slices --axis z --index 12 --out " + quoted(out) + " --db " + quoted(db));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  return test::readFile(out);
}

}  // namespace

TEST_CASE("CourseCli_ReferencedDetachedNrrd_TravelsWithItsDataFilesAndWritesOnlyInTheDataFolder") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  // Slices in a subfolder, and one slice named like the package's label map.
  writeDetached(author.path(), "ear scan.nhdr", [](int k) {
    return k == 7 ? std::string("labels.nrrd") : "slices/s" + std::to_string(k) + ".raw";
  });
  const fs::path package = authorReferencedCourse(author.path(), "ear scan.nhdr");
  const auto authorFiles = snapshot(author.path());
  const fs::path db = student / "s.db";
  auto imported = runIn("course import " + quoted(package) + " --volume " + quoted(author / "ear scan.nhdr") + " --db " + quoted(db));
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  CHECK(snapshot(author.path()) == authorFiles);  // the student's source files untouched
  // Only the database and its data folder, the header kept as volume.nhdr (its name has a space).
  const fs::path folder = student / "s-data" / "datasets" / "ear_slices";
  for (const auto& [path, bytes] : snapshot(student.path())) {
    CAPTURE(path);
    CHECK((path == "s.db" || path.rfind("s-data/datasets/ear_slices/", 0) == 0));
  }
  CHECK(test::readFile(folder / "volume" / "volume.nhdr") == authorFiles.at("ear scan.nhdr"));
  CHECK(test::readFile(folder / "volume" / "labels.nrrd") == authorFiles.at("labels.nrrd"));  // the slice
  CHECK(test::readFile(folder / "volume" / "slices" / "s31.raw") == authorFiles.at("slices/s31.raw"));
  CHECK(test::readFile(folder / "labels.nrrd") != authorFiles.at("labels.nrrd"));  // the package's label map
  // The student's copy of the scan goes; the dataset reads as the author's (the --slope 2 too).
  fs::remove_all(author / "slices");
  const std::string studentSlice = slicePng(db, student / "s.png");
  auto info = runIn("info ear_slices --json --db " + quoted(db));
  REQUIRE_MESSAGE(info.exitCode == 0, info.err);
  CHECK(nlohmann::json::parse(info.out)["dataset"]["load_options"] == "--slope 2");
  writeDetached(author.path(), "ear scan.nhdr", [](int k) {
    return k == 7 ? std::string("labels.nrrd") : "slices/s" + std::to_string(k) + ".raw";
  });
  CHECK(studentSlice == slicePng(author / "a.db", author / "a.png"));
}

TEST_CASE("CourseCli_ReferencedDetachedNrrd_WithAbsoluteDataFileNames_IsRefusedAndChangesNothing") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  const fs::path root = author.path();
  // Such a package is no longer exported (the referenced export refuses the header): one from an
  // earlier program, forged here as the package of a header with relative names whose checksum is
  // the absolute one's.
  writeDetached(root, "rel.nhdr", [&](int k) { return "slices/s" + std::to_string(k) + ".raw"; });
  writeDetached(root, "abs.nhdr", [&](int k) { return (root / "slices" / ("s" + std::to_string(k) + ".raw")).string(); });
  const fs::path package = authorReferencedCourse(root, "rel.nhdr");
  auto absoluteSum = db::checksumPath((root / "abs.nhdr").string(), "");
  REQUIRE(absoluteSum);
  auto entries = test::readTar(package);
  auto manifest = nlohmann::json::parse(test::findEntry(entries, "manifest.json")->data);
  manifest["dataset"]["source_volume_checksum"] = *absoluteSum;
  test::findEntry(entries, "manifest.json")->data = manifest.dump();
  test::writeTar(package, entries);
  // The student has another course stored already: the refused import must leave it all as it was.
  const fs::path db = student / "s.db";
  REQUIRE(runIn("course list --db " + quoted(db)).exitCode == 0);
  const auto before = snapshot(student.path());
  auto refused = runIn("course import " + quoted(package) + " --volume " + quoted(root / "abs.nhdr") + " --db " + quoted(db));
  test::checkOneLineError(refused, "lies outside the header's folder");
  CHECK(snapshot(student.path()) == before);
}

// A scan whose data files the author read from another folder (--nrrd-data: the header names them
// through "..") cannot travel by reference — a student's import copies the header's folder only —
// so that export is refused with one line naming the way out and writes nothing; the volume
// included travels and reads as the author's.
TEST_CASE("CourseCli_DetachedNrrdReadWithNrrdData_ReferencedExportRefused_IncludedTravels") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  const fs::path headerFolder = author / "header";
  fs::create_directories(headerFolder);
  writeDetached(headerFolder, "scan.nhdr", [](int k) { return "../raw/s" + std::to_string(k) + ".raw"; });
  REQUIRE(fs::exists(author / "raw" / "s31.raw"));
  const fs::path db = author / "a.db", package = author / "ear.atcourse";
  for (const std::string& args :
       {"import --volume " + quoted(headerFolder / "scan.nhdr") + " --nrrd-data " + quoted(author / "raw") + " --labels " +
            quoted(headerFolder / "seg" / "labels.nrrd") + " --names " + quoted(headerFolder / "seg" / "names.json") +
            " --name ear_slices --slope 2 --db " + quoted(db),
        "course new tour --dataset ear_slices --db " + quoted(db)}) {
    auto r = runIn(args);
    REQUIRE_MESSAGE(r.exitCode == 0, args << ": " << r.err);
  }
  const auto before = snapshot(author.path());
  auto refused = runIn("course export tour --out " + quoted(package) + " --reference-volume --db " + quoted(db));
  test::checkOneLineError(refused, "its NRRD data files lie outside the header's folder");
  CHECK(refused.err.find("without --reference-volume") != std::string::npos);
  CHECK(snapshot(author.path()) == before);
  auto exported = runIn("course export tour --out " + quoted(package) + " --db " + quoted(db));
  REQUIRE_MESSAGE(exported.exitCode == 0, exported.err);
  const fs::path studentDb = student / "s.db";
  auto imported = runIn("course import " + quoted(package) + " --db " + quoted(studentDb));
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  CHECK(slicePng(studentDb, student / "s.png") == slicePng(db, author / "a.png"));
}

// Packages exported before a detached NRRD's checksum covered its data files recorded the header's
// bytes alone: the student's header is still accepted while it is unchanged, and refused when not.
TEST_CASE("CourseCli_ReferencedDetachedNrrd_RecordedByItsHeaderAlone_IsAcceptedWhileTheHeaderIsUnchanged") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  writeDetached(author.path(), "scan.nhdr", [](int k) { return "s" + std::to_string(k) + ".raw"; });
  const fs::path package = authorReferencedCourse(author.path(), "scan.nhdr");
  auto headerOnly = db::headerOnlyNrrdChecksum((author / "scan.nhdr").string());
  REQUIRE(headerOnly);
  REQUIRE(*headerOnly);
  auto entries = test::readTar(package);
  auto manifest = nlohmann::json::parse(test::findEntry(entries, "manifest.json")->data);
  CHECK(manifest["dataset"]["source_volume_checksum"] != **headerOnly);
  manifest["dataset"]["source_volume_checksum"] = **headerOnly;
  test::findEntry(entries, "manifest.json")->data = manifest.dump();
  const fs::path legacy = author / "legacy.atcourse";
  test::writeTar(legacy, entries);

  // A changed header byte (another spacing) is not the course's volume: refused, nothing written.
  const std::string header = test::readFile(author / "scan.nhdr");
  std::string changed = header;
  changed.replace(changed.find("space origin: (0,0,0)"), 21, "space origin: (0,0,1)");
  std::ofstream(author / "scan.nhdr", std::ios::binary) << changed;
  const fs::path db = student / "s.db";
  auto refused = runIn("course import " + quoted(legacy) + " --volume " + quoted(author / "scan.nhdr") + " --db " + quoted(db));
  test::checkOneLineError(refused, "is not the course's volume");
  CHECK(snapshot(student.path()).count("s-data/datasets/ear_slices/volume/scan.nhdr") == 0);

  std::ofstream(author / "scan.nhdr", std::ios::binary) << header;
  auto imported = runIn("course import " + quoted(legacy) + " --volume " + quoted(author / "scan.nhdr") + " --db " + quoted(db));
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  CHECK(slicePng(db, student / "s.png") == slicePng(author / "a.db", author / "a.png"));
}

// On a class server the dataset's row is stored once and each lab machine keeps its own copy of a
// referenced scan: a machine whose copy was damaged imports the package again and gets it back
// (the copy replaces the files left there, where it refused them as existing before).
TEST_CASE("CourseCli_ReferencedDetachedNrrdOnAClassServer_EachLabMachinePlacesAndRepairsItsCopy") {
  if (!test::requireAppBinary("course packages")) return;
  auto url = test::freshPostgresDatabase("the class-server detached NRRD test");
  if (!url) return;
  test::TempDir author("at-author"), labA("at-lab-a"), labB("at-lab-b");
  writeDetached(author.path(), "scan.nhdr", [](int k) { return "slices/s" + std::to_string(k) + ".raw"; });
  const fs::path package = authorReferencedCourse(author.path(), "scan.nhdr");
  const std::string import = "course import " + quoted(package) + " --volume " + quoted(author / "scan.nhdr") + " --db '" + *url + "'";
  const auto folderOf = [](const fs::path& lab) {
    const fs::path servers = lab / "anatomy-tutor" / "servers";
    REQUIRE(fs::exists(servers));
    return fs::directory_iterator(servers)->path() / "datasets" / "ear_slices" / "volume";
  };
  {
    test::OnMachine machine(labA.path());
    auto imported = runIn(import);
    REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
    CHECK(test::readFile(folderOf(labA.path()) / "slices" / "s5.raw") == test::readFile(author / "slices" / "s5.raw"));
  }
  test::OnMachine machine(labB.path());
  auto placed = runIn(import);
  REQUIRE_MESSAGE(placed.exitCode == 0, placed.err);
  CHECK(placed.out.find("its files placed on this machine") != std::string::npos);
  const fs::path copy = folderOf(labB.path());
  const std::string original = test::readFile(copy / "slices" / "s5.raw");
  std::string damaged = original;
  damaged[10] = char(damaged[10] ^ 0x40);
  std::ofstream(copy / "slices" / "s5.raw", std::ios::binary) << damaged;
  fs::remove(copy / "slices" / "s6.raw");
  fs::create_symlink(author / "slices" / "s5.raw", copy / "slices" / "s6.raw");  // a link left there is replaced, not written through
  const std::string linkedBefore = test::readFile(author / "slices" / "s5.raw");
  auto repaired = runIn(import);
  REQUIRE_MESSAGE(repaired.exitCode == 0, repaired.err);
  CHECK(repaired.out.find("its files placed on this machine") != std::string::npos);
  CHECK(test::readFile(copy / "slices" / "s5.raw") == original);
  CHECK_FALSE(fs::is_symlink(copy / "slices" / "s6.raw"));
  CHECK(test::readFile(copy / "slices" / "s6.raw") == test::readFile(author / "slices" / "s6.raw"));
  CHECK(test::readFile(author / "slices" / "s5.raw") == linkedBefore);
  CHECK(test::postgresValue(*url, "SELECT COUNT(*) FROM datasets WHERE name = 'ear_slices'") == "1");
}

// A header that names its data files by absolute paths (inside its own folder, so that it imports
// without --nrrd-data) reads the author's files wherever it is copied, and one naming them through
// ".." needs folders a student's copy does not make: the referenced export is refused in one line and
// writes nothing; the included export travels. Names relative to the header's folder export as before.
TEST_CASE("CourseCli_DetachedNrrdNamingItsDataByAbsolutePaths_ReferencedExportRefused_IncludedTravels") {
  if (!test::requireAppBinary("course packages")) return;
  struct Naming {
    const char* what;
    std::function<std::string(const fs::path& folder, int k)> name;
    bool travels;
  };
  const std::vector<Naming> namings = {
      {"absolute, in its folder", [](const fs::path& f, int k) { return (f / ("s" + std::to_string(k) + ".raw")).string(); }, false},
      {"absolute for one slice", [](const fs::path& f, int k) {
         return k == 5 ? (f / "s5.raw").string() : "s" + std::to_string(k) + ".raw"; }, false},
      {"through a subfolder's ..", [](const fs::path&, int k) { return "sub/../t" + std::to_string(k) + ".raw"; }, false},
      {"relative, with ./ and a subfolder", [](const fs::path&, int k) {
         return k % 2 ? "./s" + std::to_string(k) + ".raw" : "sub/t" + std::to_string(k) + ".raw"; }, true},
  };
  for (const Naming& naming : namings) {
    CAPTURE(naming.what);
    test::TempDir author("at-author"), student("at-student");
    const fs::path folder = author / "scan";
    fs::create_directories(folder);
    writeDetached(folder, "scan.nhdr", [&](int k) { return naming.name(folder, k); });
    const fs::path db = author / "a.db", package = author / "ear.atcourse";
    for (const std::string& args :
         {"import --volume " + quoted(folder / "scan.nhdr") + " --labels " + quoted(folder / "seg" / "labels.nrrd") +
              " --names " + quoted(folder / "seg" / "names.json") + " --name ear_slices --db " + quoted(db),
          "course new tour --dataset ear_slices --db " + quoted(db)}) {
      auto r = runIn(args);
      REQUIRE_MESSAGE(r.exitCode == 0, args << ": " << r.err);
    }
    const auto before = snapshot(author.path());
    auto referenced = runIn("course export tour --out " + quoted(package) + " --reference-volume --db " + quoted(db));
    const fs::path studentDb = student / "s.db";
    if (naming.travels) {
      REQUIRE_MESSAGE(referenced.exitCode == 0, referenced.err);
      auto imported = runIn("course import " + quoted(package) + " --volume " + quoted(folder / "scan.nhdr") + " --db " +
                            quoted(studentDb));
      REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
    } else {
      test::checkOneLineError(referenced, "names its data files by absolute paths or through '..'");
      CHECK(referenced.err.find("without --reference-volume") != std::string::npos);
      CHECK(snapshot(author.path()) == before);
      auto included = runIn("course export tour --out " + quoted(package) + " --db " + quoted(db));
      REQUIRE_MESSAGE(included.exitCode == 0, included.err);
      auto imported = runIn("course import " + quoted(package) + " --db " + quoted(studentDb));
      REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
    }
    CHECK(slicePng(studentDb, student / "s.png") == slicePng(db, author / "a.png"));
  }
}
