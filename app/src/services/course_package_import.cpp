// Importing a course package (course_packages.h): read and verify into a staging folder, check
// against what is stored, commit every row in one transaction, then move the files into place.
#include <set>

#include "core/safe_name.h"
#include "course_authoring.h"
#include "course_packages.h"
#include "course_presets.h"
#include "dataset_resolver.h"
#include "db/all_or_nothing.h"
#include "db/checksum.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "db/preset_store.h"
#include "import_staging.h"
#include "lessons/course_check.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"
#include "volume/nrrd_io.h"

namespace at::app {

namespace fs = std::filesystem;

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

bool builtinName(const std::string& name) { return isBuiltinDatasetName(name) || findKnownScan(name) != nullptr; }

std::set<std::string> idsOf(const std::vector<Structure>& structures) {
  std::set<std::string> ids;
  for (const Structure& s : structures) ids.insert(s.id);
  return ids;
}

// "sha256:0123456789ab…" for messages.
std::string shortChecksum(const std::string& checksum) { return checksum.size() > 19 ? checksum.substr(0, 19) + "…" : checksum; }

// Copies the scan a user gives for a package that references it to `to`: a folder (a DICOM
// series), a file, or a detached NRRD header with the data files it names, each at its place
// relative to the header (they lie in the header's folder: nrrdDataFiles). Writes only under
// `to`'s folder; a data file named by an absolute path or through ".." stays behind, and the copy
// then fails its checksum or its load with one line. A file already at a target (left by an
// earlier copy on this machine: a lab machine placing a class server's files again) is replaced;
// a link there is removed, never followed.
Status copyVolume(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  const auto cannot = [&](const fs::path& source, const fs::path& target) {
    return fail(ErrorKind::Io, source.string() + ": cannot copy into " + target.string() + " (" + ec.message() + ")");
  };
  if (fs::is_directory(from, ec)) {
    fs::copy(from, to, fs::copy_options::recursive, ec);
    return ec ? cannot(from, to) : Status{};
  }
  fs::create_directories(to.parent_path(), ec);
  fs::copy_file(from, to, ec);
  if (ec) return cannot(from, to);
  auto dataFiles = nrrdDataFiles(from.string());
  if (!dataFiles) return tl::unexpected(dataFiles.error());
  const fs::path header = fs::weakly_canonical(fs::absolute(from), ec), folder = header.parent_path();
  std::set<fs::path> copied;
  for (const std::string& file : *dataFiles) {
    const fs::path resolved = fs::weakly_canonical(fs::absolute(file), ec);
    if (resolved == header || !copied.insert(resolved).second) continue;
    const fs::path inside = resolved.lexically_relative(folder);
    if (inside.empty() || *inside.begin() == "..") return fail(from.string() + ": data file " + file + " lies outside its folder");
    const fs::path target = to.parent_path() / inside;
    if (target == to) return fail(from.string() + ": data file " + file + " would take the place of the header's copy " + to.string());
    fs::create_directories(target.parent_path(), ec);
    std::error_code absent;  // a target that does not exist yet is no error
    if (!ec && fs::is_symlink(fs::symlink_status(target, absent))) fs::remove(target, ec);
    if (!ec) fs::copy_file(resolved, target, fs::copy_options::overwrite_existing, ec);
    if (ec) return cannot(resolved, target);
  }
  return {};
}

// The name a referenced volume is kept under in the dataset's folder: "volume" with the user's
// file's extensions (".inv3", ".nii.gz"), so that its reader is chosen as before and no outside
// name becomes a path; a detached NRRD header keeps its name in a folder "volume" of its own, with
// its data files under the names it gives them (so that no data file lands on the label map); a
// header whose name is not a plain one (core/safe_name.h) is kept as volume.nhdr.
Result<std::string> referencedVolumeName(const fs::path& given) {
  std::error_code ec;
  if (fs::is_directory(given, ec)) return std::string("volume");
  const std::string file = given.filename().string();
  auto dataFiles = nrrdDataFiles(given.string());
  if (!dataFiles) return tl::unexpected(dataFiles.error());
  if (!dataFiles->empty()) return "volume/" + (isSafeName(file) ? file : std::string("volume.nhdr"));
  const std::size_t dot = file.find('.', 1);
  const std::string name = dot == std::string::npos ? "volume" : "volume" + file.substr(dot);
  return isSafeName(name) ? name : std::string("volume");
}

// A dataset registered from the staged files: the record as it will be stored (paths relative to
// the database's folder, at the dataset's final folder).
struct StagedDataset {
  db::DatasetRecord record;
  fs::path target;  // datasets/<name>
};

Result<StagedDataset> stageDataset(db::Database& database, const package::CoursePackage& pkg, const ImportStaging& staging,
                                   const fs::path& target, const CourseImportRequest& request, const std::string& name) {
  const package::DatasetEntry& d = pkg.manifest.dataset;
  const fs::path staged = staging.datasetFolder();
  std::string volumeName = "volume.nrrd";
  if (d.source != package::VolumeSource::Included) {
    auto referenced = referencedVolumeName(request.volumePath);
    if (!referenced) return tl::unexpected(withContext(name, referenced.error()));
    volumeName = *referenced;
    if (auto ok = copyVolume(request.volumePath, staged / volumeName); !ok) return tl::unexpected(withContext(name, ok.error()));
    auto copied = db::checksumAsRecorded((staged / volumeName).string(), d.sourceVolumeChecksum);
    if (!copied) return tl::unexpected(withContext(name, copied.error()));
    if (*copied != d.sourceVolumeChecksum)
      return fail(name + ": " + request.volumePath + ": its copy in the data folder is not the course's volume (" +
                  shortChecksum(*copied) + "): a data file it names by an absolute path or through '..' does not travel");
  }
  DatasetFiles files;
  files.volumePath = (staged / volumeName).string();
  if (pkg.hasLabels) files.labelsPath = (staged / "labels.nrrd").string();
  files.id = d.name;
  if (d.reading) {
    files.intensity = d.reading->intensity;
    files.intercept = d.reading->intercept;
    files.slope = d.reading->slope;
    files.skipUnreadableFiles = d.reading->skipUnreadableFiles;
    files.modality = d.reading->modality;
  }
  auto loaded = openDatasetFiles(files);
  if (!loaded) return tl::unexpected(withContext(name + ": dataset '" + d.name + "'", loaded.error()));
  if (d.geometry && !loaded->volume.geometry.sameGridAs(*d.geometry))
    return fail(name + ": dataset '" + d.name + "': the volume's grid (" + loaded->volume.geometry.dims.toString() +
                ") is not the one the manifest records (" + d.geometry->dims.toString() + ")");
  StagedDataset out;
  out.target = target;
  db::DatasetRecord& record = out.record;
  record.name = d.name;
  record.species = d.species;
  // Read as the package says at every later open too.
  record.intensity = files.intensity;
  record.intercept = files.intercept;
  record.slope = files.slope;
  record.skipUnreadableFiles = files.skipUnreadableFiles;
  record.modality = files.modality;
  auto volumeSum = db::checksumPath(files.volumePath);
  if (!volumeSum) return tl::unexpected(volumeSum.error());
  record.volumeChecksum = *volumeSum;
  if (!files.labelsPath.empty()) {
    auto labelsSum = db::checksumPath(files.labelsPath);
    if (!labelsSum) return tl::unexpected(labelsSum.error());
    record.labelsChecksum = *labelsSum;
  }
  record.geometry = loaded->volume.geometry;
  record.orientation = record.geometry.orientationCode();
  // Stored relative to the database's folder, so that the database and its data folder move
  // together (on a class server: to each machine's folder for it).
  auto pathBase = db::datasetPathBase(database);
  if (!pathBase) return tl::unexpected(pathBase.error());
  const fs::path base = *pathBase;
  record.volumePath = (target / volumeName).lexically_relative(base).string();
  if (!files.labelsPath.empty()) record.labelsPath = (target / "labels.nrrd").lexically_relative(base).string();
  return out;
}

// Whether this machine has the files of a dataset registered with relative paths (a class
// server's dataset, imported on another machine), with the recorded checksums. A copy whose
// checksum cannot be taken (a data file missing, or resolving outside its folder through a link
// left there) is not the recorded one: it is placed again.
bool filesHere(const db::DatasetRecord& record) {
  std::error_code ec;
  if (!fs::exists(record.volumePath, ec) || (!record.labelsPath.empty() && !fs::exists(record.labelsPath, ec))) return false;
  auto volume = db::checksumPath(record.volumePath);
  if (!volume || *volume != record.volumeChecksum) return false;
  if (record.labelsPath.empty()) return true;
  auto labels = db::checksumPath(record.labelsPath);
  return labels && *labels == record.labelsChecksum;
}

// Puts the package's files (or the user's referenced volume) where the server's record of the
// dataset says they are on this machine — inside this machine's data folder for the server
// only — checked against the record's checksums.
Status placeFilesHere(const db::DatasetRecord& record, const package::CoursePackage& pkg, const CourseImportRequest& request,
                      const fs::path& assets, const std::string& name) {
  const package::DatasetEntry& d = pkg.manifest.dataset;
  for (const std::string& path : {record.volumePath, record.labelsPath})
    if (!path.empty() && !isInside(assets, path))
      return fail(ErrorKind::Conflict, name + ": dataset '" + d.name + "' on the server is read from " + path +
                                           ", outside this machine's data folder " + assets.string() +
                                           " (registered from files, not from a course package)");
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
  if (!filesHere(record))
    return fail(ErrorKind::Conflict, name + ": dataset '" + d.name + "': the files are not those the server recorded (" +
                                         shortChecksum(record.volumeChecksum) + ")");
  return {};
}

}  // namespace

Result<CourseImportReport> importCoursePackage(LearningSession& session, const CourseImportRequest& request) {
  db::Database& database = session.database();
  const std::string name = request.package.string();
  auto assets = courseAssetDirectory(database);
  if (assets) {
    // What an earlier import left when it was killed: finished or removed before this one.
    if (auto recovered = recoverStaging(database, *assets); !recovered) return tl::unexpected(recovered.error());
  }
  auto staging = ImportStaging::make(assets ? *assets : fs::temp_directory_path());
  if (!staging) return tl::unexpected(staging.error());
  package::ReadOptions options;
  options.extractTo = staging->datasetFolder();
  auto pkg = package::readPackageFile(request.package, options);
  if (!pkg) return tl::unexpected(pkg.error());
  importCrashPoint("extracted");
  const package::DatasetEntry& d = pkg->manifest.dataset;

  // The course as stored: its steps name the package's presets by the course's keys.
  std::set<std::string> packaged;
  for (const package::PackagedPreset& p : pkg->presets) packaged.insert(p.id);
  lessons::Course course = withCoursePresetKeys(pkg->course, packaged);

  CourseImportReport report;
  report.courseId = course.id;
  report.courseTitle = course.title;
  report.version = course.version;
  report.datasetId = d.name;
  if (auto ok = checkCourseFits(session.curriculum(), course, report.outcome); !ok) {
    // The same package stored by a program that kept presets under their plain ids: unchanged.
    db::SeedOutcome stored = db::SeedOutcome::Added;
    if (packaged.empty() || !checkCourseFits(session.curriculum(), pkg->course, stored) || stored != db::SeedOutcome::Unchanged)
      return tl::unexpected(withContext(name, ok.error()));
    course = pkg->course;
    report.outcome = stored;
  }

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
      // (a package from before checksums covered a detached NRRD's data files recorded its header's)
      auto sum = db::checksumAsRecorded(request.volumePath, d.sourceVolumeChecksum);
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
  if (auto ok = lessons::checkStructureReferences(course, idsOf(structures), name + ": course.json"); !ok)
    return tl::unexpected(ok.error());
  if (existing) {
    auto have = db::datasetStructures(database, existing->id);
    if (!have) return tl::unexpected(have.error());
    if (auto ok = lessons::checkStructureReferences(course, idsOf(*have), name + ": course.json (on the dataset already here)"); !ok)
      return tl::unexpected(ok.error());
  }

  // On a class server the dataset's row may come from another machine's import: its files go
  // under this machine's folder for the server, at the paths the row records.
  const bool server = db::isPostgresUrl(db::pathOf(database));
  if (server && existing) {
    if (!filesHere(*existing)) {
      if (!assets) return tl::unexpected(withContext(name, assets.error()));
      if (auto placed = placeFilesHere(*existing, *pkg, request, *assets, name); !placed) return tl::unexpected(placed.error());
      report.dataset = DatasetAction::PlacedHere;
      report.datasetFolder = fs::path(existing->volumePath).parent_path();
    }
  }

  std::optional<StagedDataset> fresh;
  if (d.source != package::VolumeSource::Builtin && !existing) {
    if (!assets) return tl::unexpected(withContext(name, assets.error()));
    auto target = confinedPath(*assets, {"datasets", d.name}, name + ": manifest.json: dataset.name");
    if (!target) return tl::unexpected(target.error());
    std::error_code ec;
    if (fs::exists(fs::symlink_status(*target, ec)))
      return fail(ErrorKind::Conflict, name + ": " + target->string() +
                                           " exists, but no stored dataset is named '" + d.name +
                                           "': move that folder away (nothing was changed)");
    auto staged = stageDataset(database, *pkg, *staging, *target, request, name);
    if (!staged) return tl::unexpected(staged.error());
    fresh = std::move(*staged);
    if (auto ok = staging->recordTarget(d.name); !ok) return tl::unexpected(ok.error());
    report.dataset = DatasetAction::Imported;
    report.datasetFolder = *target;
  }

  // The package's presets, for this course only; written again only with a new course version.
  std::vector<db::StoredPreset> presets;
  if (report.outcome != db::SeedOutcome::Unchanged)
    for (const package::PackagedPreset& p : pkg->presets)
      presets.push_back({coursePresetKey(course.id, p.id), p.preset.structure, render::toString(p.preset.mode),
                         render::presetToJson(p.preset)});  // re-serialised: the database keeps content, not padding

  importCrashPoint("before-commit");
  const std::string source = "package " + request.package.filename().string() + " sha256:" + pkg->manifest.find("course.json")->sha256;
  auto stored = db::writeAllOrNothing(database, [&]() -> Status {
    if (fresh) {
      auto id = db::registerDataset(database, fresh->record, pkg->structures);
      if (!id) return tl::unexpected(id.error());
    }
    importCrashPoint("in-transaction");
    for (const db::StoredPreset& p : presets)
      if (auto ok = db::savePreset(database, p); !ok) return ok;
    auto outcome = db::storeCourse(database, course, source);
    if (!outcome) return tl::unexpected(withContext(name, outcome.error()));
    report.outcome = *outcome;
    return {};
  });
  if (!stored) return tl::unexpected(stored.error());
  importCrashPoint("after-commit");
  for (const db::StoredPreset& p : presets) report.presetsStored.push_back(p.id);
  if (fresh)
    if (auto moved = staging->moveInto(fresh->target); !moved)
      return tl::unexpected(withContext(name + ": stored, but its files were not moved into place (the program finishes that when it next imports or opens the database)", moved.error()));
  return report;
}

}  // namespace at::app
