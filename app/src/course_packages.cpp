#include "course_packages.h"

#include <cstdlib>
#include <map>
#include <set>

#include "db/checksum.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "db/preset_store.h"
#include "course_authoring.h"
#include "dataset_resolver.h"
#include "lessons/course_check.h"
#include "lessons/course_json.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"

namespace at::app {

namespace fs = std::filesystem;

namespace {

// A fresh folder named "<prefix>XXXXXX" in `parent`, removed with everything in it at the end of
// the scope unless kept.
class ScratchFolder {
 public:
  static Result<ScratchFolder> make(const fs::path& parent, const std::string& prefix) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    std::string pattern = (parent / (prefix + "XXXXXX")).string();
    if (ec || !::mkdtemp(pattern.data())) return fail(ErrorKind::Io, parent.string() + ": cannot create a working folder");
    return ScratchFolder(pattern);
  }
  ScratchFolder(ScratchFolder&& other) noexcept : path_(std::move(other.path_)) { other.path_.clear(); }
  ScratchFolder(const ScratchFolder&) = delete;
  ~ScratchFolder() {
    std::error_code ec;
    if (!path_.empty()) fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  explicit ScratchFolder(fs::path path) : path_(std::move(path)) {}
  fs::path path_;
};

bool builtinName(const std::string& name) { return isBuiltinDatasetName(name) || findKnownScan(name) != nullptr; }

std::set<std::string> idsOf(const std::vector<Structure>& structures) {
  std::set<std::string> ids;
  for (const Structure& s : structures) ids.insert(s.id);
  return ids;
}

// The preset ids a course's steps name, sorted.
std::set<std::string> presetIdsOf(const lessons::Course& course) {
  std::set<std::string> ids;
  for (const lessons::Lesson& lesson : course.lessons)
    for (const lessons::Step& step : lesson.steps) {
      if (step.kind == lessons::StepKind::Show && !step.show.presetId.empty()) ids.insert(step.show.presetId);
      if (step.kind == lessons::StepKind::Question && step.scene && !step.scene->presetId.empty())
        ids.insert(step.scene->presetId);
    }
  return ids;
}

// Each named preset the database or the shipped library has (a name neither has is left to the
// structure's default preset, as when the course is played).
Result<std::vector<package::PackagedPreset>> coursePresets(db::Database& database, const render::PresetLibrary& library,
                                                          const lessons::Course& course) {
  std::vector<package::PackagedPreset> out;
  for (const std::string& id : presetIdsOf(course)) {
    auto stored = db::findPreset(database, id);
    if (!stored) return tl::unexpected(stored.error());
    std::string text;
    if (*stored) {
      text = (*stored)->json;
    } else if (fs::is_regular_file(library.dir() / (id + ".json"))) {
      auto loaded = library.load(id);
      if (!loaded) return tl::unexpected(loaded.error());
      text = render::presetToJson(*loaded);
    } else {
      continue;
    }
    auto preset = render::parsePreset(text, "preset '" + id + "'");
    if (!preset) return tl::unexpected(preset.error());
    out.push_back({id, *preset, text});
  }
  return out;
}

}  // namespace

Result<fs::path> courseAssetDirectory(const db::Database& database) {
  const fs::path file = db::pathOf(database);
  if (db::isPostgresUrl(file.string())) {
    auto base = db::datasetPathBase(database);
    if (!base) return tl::unexpected(base.error());
    return fs::path(*base);
  }
  if (file.empty() || db::pathOf(database) == ":memory:") return fail("an in-memory database has no data folder for course assets");
  return fs::absolute(file).parent_path() / (file.stem().string() + "-data");
}

Result<CourseExportReport> exportCourse(LearningSession& session, const render::PresetLibrary& library,
                                        const CourseExportRequest& request) {
  auto course = session.curriculum().course(request.courseId);
  if (!course) return tl::unexpected(course.error());
  if (request.out.empty()) return fail("an output file (--out F.atcourse) is required");
  db::Database& database = session.database();

  package::PackageInput input;
  input.course = *course;
  input.createdBy = std::string("anatomy-tutor ") + AT_VERSION;
  auto presets = coursePresets(database, library, *course);
  if (!presets) return tl::unexpected(presets.error());
  input.presets = std::move(*presets);
  input.dataset.name = course->datasetId;

  std::optional<ScratchFolder> scratch;
  if (builtinName(course->datasetId)) {
    if (request.referenceVolume) return fail("dataset '" + course->datasetId + "' is built in: there is no volume to reference");
    input.dataset.source = package::VolumeSource::Builtin;
  } else {
    auto record = db::findDataset(database, course->datasetId);
    if (!record) return tl::unexpected(record.error());
    if (!*record)
      return fail(ErrorKind::NotFound, "course '" + course->id + "': dataset '" + course->datasetId + "' is not imported here");
    DatasetRequest open;
    open.name = course->datasetId;
    open.database = &database;
    auto dataset = openNamedDataset(open);
    if (!dataset) return tl::unexpected(dataset.error());
    if (auto ok = lessons::checkStructureReferences(*course, idsOf(dataset->structures), "course '" + course->id + "'"); !ok)
      return tl::unexpected(ok.error());
    const fs::path outFolder = fs::absolute(request.out).parent_path();
    auto made = ScratchFolder::make(outFolder, "." + request.out.filename().string() + ".");
    if (!made) return tl::unexpected(made.error());
    scratch.emplace(std::move(*made));
    const bool withLabels = !(*record)->labelsPath.empty();
    auto files = package::writeDatasetFiles(*dataset, scratch->path(), withLabels);
    if (!files) return tl::unexpected(files.error());
    package::DatasetEntry& d = input.dataset;
    d.source = request.referenceVolume ? package::VolumeSource::Reference : package::VolumeSource::Included;
    d.species = (*record)->species;
    d.geometry = dataset->volume.geometry;
    d.sourceVolumeChecksum = (*record)->volumeChecksum;
    d.sourceLabelsChecksum = (*record)->labelsChecksum;
    if (request.referenceVolume) {
      d.referenceFileName = fs::path((*record)->volumePath).filename().string();
      d.referenceNote = request.referenceNote;
    } else {
      input.volumeFile = files->volume;
    }
    input.labelsFile = files->labels;
    input.structures = dataset->structures;
  }
  if (auto ok = package::writePackage(request.out, input); !ok) return tl::unexpected(ok.error());
  CourseExportReport report;
  report.file = request.out;
  std::error_code ec;
  report.bytes = fs::file_size(request.out, ec);
  report.source = input.dataset.source;
  report.datasetId = course->datasetId;
  report.presets = input.presets.size();
  report.structures = input.structures.size();
  return report;
}

const char* toString(DatasetAction action) {
  switch (action) {
    case DatasetAction::Builtin: return "built in";
    case DatasetAction::Imported: return "imported";
    case DatasetAction::AlreadyPresent: return "already present";
    case DatasetAction::PlacedHere: return "on the server already; its files placed on this machine";
  }
  return "?";
}

namespace {

// "sha256:0123456789ab…" for messages.
std::string shortChecksum(const std::string& checksum) { return checksum.size() > 19 ? checksum.substr(0, 19) + "…" : checksum; }

// Copies a file or a folder (a DICOM series) to `to`.
Status copyVolume(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  if (fs::is_directory(from, ec)) fs::copy(from, to, fs::copy_options::recursive, ec);
  else fs::copy_file(from, to, ec);
  if (ec) return fail(ErrorKind::Io, from.string() + ": cannot copy into " + to.string() + " (" + ec.message() + ")");
  return {};
}

// Registers the package's dataset from its extracted files (and, for a reference, the user's
// volume), moved or copied to `folder`.
Result<db::DatasetRecord> registerPackagedDataset(db::Database& database, const package::CoursePackage& pkg, const fs::path& folder,
                                                  const CourseImportRequest& request, const std::string& name) {
  const package::DatasetEntry& d = pkg.manifest.dataset;
  std::error_code ec;
  fs::remove_all(folder, ec);  // a folder left by an import that failed after extracting
  fs::create_directories(folder, ec);
  if (ec) return fail(ErrorKind::Io, folder.string() + ": cannot create (" + ec.message() + ")");
  db::DatasetRecord record;
  record.name = d.name;
  record.species = d.species;
  if (d.source == package::VolumeSource::Included) {
    record.volumePath = (folder / "volume.nrrd").string();
    fs::rename(pkg.volumeFile, record.volumePath, ec);
  } else {
    const fs::path given = request.volumePath;
    record.volumePath = (folder / given.filename()).string();
    if (auto ok = copyVolume(given, record.volumePath); !ok) return tl::unexpected(ok.error());
  }
  if (ec) return fail(ErrorKind::Io, record.volumePath + ": cannot move into place (" + ec.message() + ")");
  if (pkg.hasLabels) {
    record.labelsPath = (folder / "labels.nrrd").string();
    fs::rename(pkg.labelsFile, record.labelsPath, ec);
    if (ec) return fail(ErrorKind::Io, record.labelsPath + ": cannot move into place (" + ec.message() + ")");
  }
  DatasetFiles files;
  files.volumePath = record.volumePath;
  files.labelsPath = record.labelsPath;
  files.id = d.name;
  auto loaded = openDatasetFiles(files);
  if (!loaded) return tl::unexpected(withContext(name + ": dataset '" + d.name + "'", loaded.error()));
  if (d.geometry && !loaded->volume.geometry.sameGridAs(*d.geometry))
    return fail(name + ": dataset '" + d.name + "': the volume's grid (" + loaded->volume.geometry.dims.toString() +
                ") is not the one the manifest records (" + d.geometry->dims.toString() + ")");
  auto volumeSum = db::checksumPath(record.volumePath);
  if (!volumeSum) return tl::unexpected(volumeSum.error());
  record.volumeChecksum = *volumeSum;
  if (!record.labelsPath.empty()) {
    auto labelsSum = db::checksumPath(record.labelsPath);
    if (!labelsSum) return tl::unexpected(labelsSum.error());
    record.labelsChecksum = *labelsSum;
  }
  record.geometry = loaded->volume.geometry;
  record.orientation = record.geometry.orientationCode();
  // Stored relative to the database's folder, so that the database and its data folder move
  // together (on a class server: to each machine's folder for it, where every machine that
  // imports the package puts the files).
  db::DatasetRecord stored = record;
  auto pathBase = db::datasetPathBase(database);
  if (!pathBase) return tl::unexpected(pathBase.error());
  const fs::path base = *pathBase;
  stored.volumePath = fs::path(record.volumePath).lexically_relative(base).string();
  if (!record.labelsPath.empty()) stored.labelsPath = fs::path(record.labelsPath).lexically_relative(base).string();
  auto id = db::registerDataset(database, stored, pkg.structures);
  if (!id) return tl::unexpected(id.error());
  record.id = *id;
  return record;
}

// Whether this machine has the files of a dataset registered with relative paths (a class
// server's dataset, imported on another machine), with the recorded checksums.
Result<bool> filesHere(const db::DatasetRecord& record) {
  std::error_code ec;
  if (!fs::exists(record.volumePath, ec) || (!record.labelsPath.empty() && !fs::exists(record.labelsPath, ec))) return false;
  auto volume = db::checksumPath(record.volumePath);
  if (!volume) return tl::unexpected(volume.error());
  if (*volume != record.volumeChecksum) return false;
  if (record.labelsPath.empty()) return true;
  auto labels = db::checksumPath(record.labelsPath);
  if (!labels) return tl::unexpected(labels.error());
  return *labels == record.labelsChecksum;
}

// Puts the package's files (or the user's referenced volume) where the server's record of the
// dataset says they are on this machine, checked against the record's checksums.
Status placeFilesHere(const db::DatasetRecord& record, const package::CoursePackage& pkg, const CourseImportRequest& request,
                      const std::string& name) {
  const package::DatasetEntry& d = pkg.manifest.dataset;
  std::error_code ec;
  fs::create_directories(fs::path(record.volumePath).parent_path(), ec);
  if (ec) return fail(ErrorKind::Io, fs::path(record.volumePath).parent_path().string() + ": cannot create (" + ec.message() + ")");
  fs::remove_all(record.volumePath, ec);
  if (d.source == package::VolumeSource::Included) {
    fs::rename(pkg.volumeFile, record.volumePath, ec);
    if (ec) return fail(ErrorKind::Io, record.volumePath + ": cannot move into place (" + ec.message() + ")");
  } else if (request.volumePath.empty()) {
    return fail(ErrorKind::NotFound, name + ": the package does not include its volume: give the scan with --volume PATH (" +
                                         d.referenceFileName + ", " + shortChecksum(record.volumeChecksum) + ")");
  } else if (auto copied = copyVolume(request.volumePath, record.volumePath); !copied) {
    return copied;
  }
  if (!record.labelsPath.empty()) {
    if (!pkg.hasLabels) return fail(name + ": dataset '" + d.name + "' has a label map on the server; the package has none");
    fs::create_directories(fs::path(record.labelsPath).parent_path(), ec);
    fs::remove(record.labelsPath, ec);
    fs::rename(pkg.labelsFile, record.labelsPath, ec);
    if (ec) return fail(ErrorKind::Io, record.labelsPath + ": cannot move into place (" + ec.message() + ")");
  }
  auto here = filesHere(record);
  if (!here) return tl::unexpected(here.error());
  if (!*here)
    return fail(ErrorKind::Conflict, name + ": dataset '" + d.name + "': the files are not those the server recorded (" +
                                         shortChecksum(record.volumeChecksum) + ")");
  return {};
}

}  // namespace

Result<CourseImportReport> importCoursePackage(LearningSession& session, const CourseImportRequest& request) {
  db::Database& database = session.database();
  const std::string name = request.package.string();
  auto assets = courseAssetDirectory(database);
  auto staging = ScratchFolder::make(assets ? *assets : fs::temp_directory_path(), "staging-");
  if (!staging) return tl::unexpected(staging.error());
  package::ReadOptions options;
  options.extractTo = staging->path();
  auto pkg = package::readPackageFile(request.package, options);
  if (!pkg) return tl::unexpected(pkg.error());
  const package::DatasetEntry& d = pkg->manifest.dataset;

  CourseImportReport report;
  report.courseId = pkg->course.id;
  report.courseTitle = pkg->course.title;
  report.version = pkg->course.version;
  report.datasetId = d.name;
  if (auto ok = checkCourseFits(session.curriculum(), pkg->course, report.outcome); !ok)
    return tl::unexpected(withContext(name, ok.error()));

  // The dataset: built in, already here (the same volume), or registered from the package.
  std::optional<db::DatasetRecord> existing;
  if (d.source == package::VolumeSource::Builtin) {
    if (!builtinName(d.name))
      return fail(ErrorKind::NotFound, name + ": the course's dataset '" + d.name + "' is not built into this program");
    report.dataset = DatasetAction::Builtin;
  } else {
    if (builtinName(d.name)) return fail(name + ": dataset '" + d.name + "' is a built-in dataset's name");
    auto found = db::findDataset(database, d.name);
    if (!found) return tl::unexpected(found.error());
    const package::PackagedFile* volume = pkg->manifest.find("dataset/volume.nrrd");
    if (*found) {
      const std::string have = (*found)->volumeChecksum;
      if (have != d.sourceVolumeChecksum && !(volume && have == "sha256:" + volume->sha256))
        return fail(ErrorKind::Conflict, name + ": a dataset named '" + d.name + "' is already imported with another volume (" +
                                             shortChecksum(have) + "; the package's is " + shortChecksum(d.sourceVolumeChecksum) + ")");
      existing = **found;
      report.dataset = DatasetAction::AlreadyPresent;
    } else if (d.source == package::VolumeSource::Reference) {
      const std::string wanted = d.referenceFileName + ", " + shortChecksum(d.sourceVolumeChecksum) +
                                 (d.referenceNote.empty() ? "" : "; " + d.referenceNote);
      if (request.volumePath.empty())
        return fail(ErrorKind::NotFound, name + ": the package does not include its volume: give the scan with --volume PATH (" + wanted + ")");
      auto sum = db::checksumPath(request.volumePath);
      if (!sum) return tl::unexpected(sum.error());
      if (*sum != d.sourceVolumeChecksum)
        return fail(name + ": " + request.volumePath + " is not the course's volume: expected " + wanted + ", the file has " +
                    shortChecksum(*sum));
    }
  }
  const std::vector<Structure> structures = [&] {
    if (d.source != package::VolumeSource::Builtin) return pkg->structures;
    auto s = session.structures(d.name);
    return s ? *s : std::vector<Structure>{};
  }();
  if (auto ok = lessons::checkStructureReferences(pkg->course, idsOf(structures), name + ": course.json"); !ok)
    return tl::unexpected(ok.error());
  if (existing) {
    auto have = db::datasetStructures(database, existing->id);
    if (!have) return tl::unexpected(have.error());
    if (auto ok = lessons::checkStructureReferences(pkg->course, idsOf(*have), name + ": course.json (on the dataset already here)"); !ok)
      return tl::unexpected(ok.error());
  }

  // On a class server the dataset's row may come from another machine's import: its files go
  // under this machine's folder for the server, at the paths the row records.
  const bool server = db::isPostgresUrl(db::pathOf(database));
  if (server && existing) {
    auto here = filesHere(*existing);
    if (!here) return tl::unexpected(withContext(name, here.error()));
    if (!*here) {
      // Only files a package import put in the machines' folders are placed; a dataset someone
      // registered from their own files elsewhere is left alone.
      if (!assets) return tl::unexpected(withContext(name, assets.error()));
      const std::string under = fs::path(existing->volumePath).lexically_relative(*assets).string();
      if (under.empty() || under.rfind("..", 0) == 0)
        return fail(ErrorKind::Conflict, name + ": dataset '" + d.name + "' on the server is read from " + existing->volumePath +
                                             ", which this machine lacks or has with other content (registered from files, not "
                                             "from a course package)");
      if (auto placed = placeFilesHere(*existing, *pkg, request, name); !placed) return tl::unexpected(placed.error());
      report.dataset = DatasetAction::PlacedHere;
      report.datasetFolder = fs::path(existing->volumePath).parent_path();
    }
  }

  if (d.source != package::VolumeSource::Builtin && !existing) {
    if (!assets) return tl::unexpected(withContext(name, assets.error()));
    report.datasetFolder = *assets / "datasets" / d.name;
    auto record = registerPackagedDataset(database, *pkg, report.datasetFolder, request, name);
    if (!record) {
      std::error_code ec;
      fs::remove_all(report.datasetFolder, ec);
      return tl::unexpected(record.error());
    }
    report.dataset = DatasetAction::Imported;
  }

  for (const package::PackagedPreset& p : pkg->presets) {
    auto stored = db::findPreset(database, p.id);
    if (!stored) return tl::unexpected(stored.error());
    if (*stored) {
      if ((*stored)->json != p.json) ++report.presetsKept;
      continue;
    }
    db::StoredPreset preset{p.id, p.preset.structure, render::toString(p.preset.mode), p.json};
    if (auto ok = db::savePreset(database, preset); !ok) return tl::unexpected(ok.error());
    ++report.presetsAdded;
  }
  auto outcome = db::storeCourse(database, pkg->course, "package " + request.package.filename().string() + " sha256:" +
                                                            pkg->manifest.find("course.json")->sha256);
  if (!outcome) return tl::unexpected(withContext(name, outcome.error()));
  report.outcome = *outcome;
  return report;
}

}  // namespace at::app
