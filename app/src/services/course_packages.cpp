#include "course_packages.h"

#include <cstdlib>
#include <map>
#include <set>

#include "db/checksum.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "db/preset_store.h"
#include "core/safe_name.h"
#include "course_authoring.h"
#include "course_presets.h"
#include "dataset_resolver.h"
#include "lessons/course_check.h"
#include "lessons/course_json.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"
#include "volume/nrrd_io.h"

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
// structure's default preset, as when the course is played), under the id the package gives it:
// a preset stored for the course ("<course>/<id>", course_presets.h) travels as "<id>".
Result<std::vector<package::PackagedPreset>> coursePresets(db::Database& database, const render::PresetLibrary& library,
                                                          const lessons::Course& course) {
  std::vector<package::PackagedPreset> out;
  const std::string prefix = course.id + "/";
  for (const std::string& id : presetIdsOf(course)) {
    const std::string packaged = id.rfind(prefix, 0) == 0 ? id.substr(prefix.size()) : id;
    if (auto ok = checkSafeName("course '" + course.id + "': preset", packaged); !ok) return tl::unexpected(ok.error());
    auto stored = db::findPreset(database, id);
    if (!stored) return tl::unexpected(stored.error());
    std::string text;
    if (*stored) {
      text = (*stored)->json;
    } else if (isSafeName(id) && fs::is_regular_file(library.dir() / (id + ".json"))) {
      auto loaded = library.load(id);
      if (!loaded) return tl::unexpected(loaded.error());
      text = render::presetToJson(*loaded);
    } else {
      continue;
    }
    auto preset = render::parsePreset(text, "preset '" + id + "'");
    if (!preset) return tl::unexpected(preset.error());
    out.push_back({packaged, *preset, text});
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
  input.course = withoutCoursePresetKeys(*course);
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
    // The importer reads the volume file with the options that give this dataset's values: the
    // author's own for a referenced file, those of the written int16 NRRD for an included one.
    if (request.referenceVolume) {
      d.referenceFileName = fs::path((*record)->volumePath).filename().string();
      d.referenceNote = request.referenceNote;
      const db::DatasetRecord& r = **record;
      // A student's course import copies a detached NRRD header with the data files in its own
      // folder (copyVolume); files the author read from another folder (--nrrd-data) cannot follow.
      if (!r.dataFolder.empty())
        if (auto confined = nrrdDataFiles(r.volumePath); !confined)
          return fail("dataset '" + course->datasetId + "': its NRRD data files lie outside the header's folder (imported with " +
                      "--nrrd-data " + r.dataFolder + "), where no student's course import can place them: export it " +
                      "without --reference-volume to include the volume");
      // A header naming its data files by absolute paths reads the author's files wherever it is
      // copied (on a student's machine: nothing, or files that are not the scan's); one naming them
      // through ".." needs folders the student's copy does not make.
      auto relative = nrrdDataFilesRelativeToHeader(r.volumePath);
      if (!relative) return tl::unexpected(relative.error());
      if (!*relative)
        return fail("dataset '" + course->datasetId + "': its NRRD header " + r.volumePath +
                    " names its data files by absolute paths or through '..', which a student's copy of its folder " +
                    "cannot follow: export it without --reference-volume to include the volume");
      if (r.intensity != IntensityChoice::Auto || r.intercept || r.slope || r.skipUnreadableFiles || !r.modality.empty())
        d.reading = package::VolumeReading{r.intensity, r.intercept, r.slope, r.skipUnreadableFiles, r.modality};
    } else {
      input.volumeFile = files->volume;
      d.reading = package::includedVolumeReading(*dataset);
      if (d.reading)
        if (auto ok = checkRescale(d.reading->intercept.value_or(0), d.reading->slope.value_or(1)); !ok)
          return fail("dataset '" + course->datasetId + "': its values are stored scaled beyond what a package records (" +
                      ok.error().message + "): export it with --reference-volume");
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

}  // namespace at::app
