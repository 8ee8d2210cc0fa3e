// anatomy-tutor course: authoring and sharing courses — new, validate, import (a course JSON or a
// .atcourse package), export, list. The logic is in course_authoring.h and course_packages.h.
#include <cstdio>

#include "cli_args.h"
#include "commands.h"
#include "core/strings.h"
#include "course_authoring.h"
#include "course_packages.h"
#include "db/connection.h"
#include "dataset_resolver.h"
#include "shown_dataset.h"
#include "db/dataset_store.h"
#include "lessons/exam.h"
#include "lessons/course_check.h"
#include "lessons/course_json.h"
#include "question_visibility.h"
#include "render/preset.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"
#include "printable_output.h"

namespace at::app {

namespace {

namespace fs = std::filesystem;

constexpr const char* kCourseHelp =
    "usage: anatomy-tutor course new ID --dataset DATASET [--title TEXT] [--out F.json]\n"
    "       anatomy-tutor course validate F.json [--skip-view-check]\n"
    "       anatomy-tutor course import F.json|F.atcourse [--volume PATH]\n"
    "       anatomy-tutor course export ID --out F.atcourse [--reference-volume [--note TEXT]]\n"
    "       anatomy-tutor course list\n"
    "       (each also takes --db PATH)\n\n"
    "Courses are written as JSON (data/courses/README.md) or in the desktop's course editor, and\n"
    "shared as course packages: one .atcourse file (a tar archive) holding the course, the presets\n"
    "its steps name, the dataset's structures and label map and its volume, with a manifest of\n"
    "SHA-256 checksums and a format version.\n\n"
    "  new       a starter course on DATASET (a tour of its structures: show each, then name it):\n"
    "            stored, or with --out only written as JSON to edit and then `course import`\n"
    "  validate  checks a course file: its form (errors name the field by path) and, when its dataset\n"
    "            is here, every structure it names and that every locate question can be answered in\n"
    "            its own view (a click on the target's centre picks it, and the view draws the bone\n"
    "            where the target is, not blackness; one WDT per region on the CPU:\n"
    "            --skip-view-check leaves that out)\n"
    "  import    stores a course file (a newer version replaces the stored one; an older one, other\n"
    "            content under the same version, or ids another course uses are refused), or verifies\n"
    "            and installs a package: its dataset's files go into the database's data folder\n"
    "            (<db stem>-data/datasets/NAME), so moving or deleting the package breaks nothing.\n"
    "            --volume gives the scan a package only references (checked by its checksum)\n"
    "  export    writes a stored course as a package; --reference-volume leaves an imported volume\n"
    "            out (for scans that may not be redistributed): the package records its checksum,\n"
    "            file name and --note (where to get it), and import asks for it\n"
    "  list      the stored courses\n";

int runNew(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("course new: give one course ID (see --help)");
  const auto dataset = args.value("dataset");
  if (!dataset) return reportError("course new: --dataset DATASET is required");
  auto session = LearningSession::open(args.db());
  if (!session) return reportError("course new: " + session.error().message);
  auto course = starterCourse(**session, args.positional()[1], *dataset, args.valueOr("title", ""));
  if (!course) return reportError("course new: " + course.error().message);
  // With --out the starter is a draft to edit: written, not stored, so `course import FILE` of the
  // edited file adds it (storing it here would make that import a conflict at version 1).
  if (auto out = args.value("out")) {
    if (auto ok = writeCourseJson(*course, *out); !ok) return reportError("course new: " + ok.error().message);
  } else if (auto stored = saveCourse(**session, *course, "course new"); !stored) {
    return reportError("course new: " + stored.error().message);
  }
  terminalPrintf("course '%s' (%s) on '%s': %s, %s%s\n", course->id.c_str(), rowCell(course->title).c_str(),
              course->datasetId.c_str(), str::countOf(long(course->lessons.size()), "lesson").c_str(),
              str::countOf(long(course->lessons.front().steps.size()), "step").c_str(),
              args.has("out") ? (", written to " + *args.value("out") + " (not stored: edit it, then `course import` it)").c_str()
                              : ", stored");
  return 0;
}

int runValidate(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("course validate: give one course file");
  const fs::path file = args.positional()[1];
  auto course = lessons::loadCourseJson(file);
  if (!course) return reportError(course.error().message);
  std::size_t questions = 0, steps = 0;
  for (const auto& lesson : course->lessons) {
    steps += lesson.steps.size();
    for (const auto& step : lesson.steps) questions += step.kind == lessons::StepKind::Question;
  }
  // An exam asking more items than its pool holds (examPoolSize) can never be drawn.
  int warnings = 0;
  for (const lessons::ExamSpec& exam : course->exams)
    if (const std::size_t pool = lessons::examPoolSize(exam, &*course); std::size_t(exam.count) > pool) {
      terminalFprintf(stderr,
                      "%s: warning: exam '%s' asks %d items, but its pool holds only %zu (%zu structures, %zu kinds; a "
                      "structure is located only where a lesson of the course locates it): it cannot be drawn\n",
                      file.string().c_str(), exam.id.c_str(), exam.count, pool, exam.structures.size(), exam.kinds.size());
      ++warnings;
    }
  // Structures are checked when the dataset can be opened here without changing anything.
  std::string structures = "structures not checked: dataset '" + course->datasetId + "' is not here";
  // A known scan counts as here once fetched (scripts/fetch-scans.sh) and labelled (scripts/label-scans.sh).
  const KnownScan* scan = findKnownScan(course->datasetId);
  if (scan) structures += " (fetch it with scripts/fetch-scans.sh and label it with scripts/label-scans.sh)";
  const bool builtin = isBuiltinDatasetName(course->datasetId) ||
                       (scan && locateKnownScan(*scan) && cachedKnownScanLabels(*scan));
  std::optional<db::Connection> database;
  if (!builtin) {
    auto existing = db::openExistingDatabase(args.db());
    if (!existing) return reportError("course validate: " + existing.error().message);
    if (*existing) database.emplace(std::move(**existing));
  }
  if (builtin || (database && db::findDataset(*database, course->datasetId).value_or(std::nullopt))) {
    auto session = LearningSession::open(args.db());
    if (!session) return reportError("course validate: " + session.error().message);
    if (auto ok = checkCourseAgainstDataset(**session, *course, file.string()); !ok) return reportError(ok.error().message);
    structures = "structures checked against dataset '" + course->datasetId + "'";
    if (!args.has("skip-view-check")) {
      DatasetRequest request;
      request.name = course->datasetId;
      request.database = &(*session)->database();
      // Checked in the views a student sees: the CT table and headrest left out (shown_dataset.h).
      auto shown = openDatasetForViewing(request);
      if (!shown) return reportError("course validate: " + shown.error().message);
      auto checks = checkLocateQuestions(shown->dataset, *course, render::PresetLibrary(defaultPresetsDir()));
      if (!checks) return reportError(file.string() + ": " + checks.error().message);
      int answerable = 0;
      for (const LocateCheck& c : *checks) {
        if (c.answerable) ++answerable;
        else terminalFprintf(stderr, "%s: %s (%s): not answerable: %s\n", file.string().c_str(), c.path.c_str(),
                          c.questionId.c_str(), c.problem.c_str());
      }
      if (answerable != int(checks->size())) {
        return reportError(file.string() + ": " + std::to_string(checks->size() - std::size_t(answerable)) + " of " +
                           str::countOf(long(checks->size()), "locate question") +
                           " cannot be answered in their views (move the view or the region; see above)");
      }
      structures += "; " + str::countOf(long(checks->size()), "locate question") + " answerable in its view";
    }
  }
  if (warnings > 0) structures += "; " + str::countOf(warnings, "warning") + " (see above)";
  terminalPrintf("%s: valid: course '%s' version %d on '%s': %s, %s, %s; %s\n", file.string().c_str(),
              course->id.c_str(), course->version, course->datasetId.c_str(),
              str::countOf(long(course->lessons.size()), "lesson").c_str(), str::countOf(long(steps), "step").c_str(),
              str::countOf(long(questions), "question").c_str(), structures.c_str());
  return 0;
}

int runImportFile(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("course import: give one course file (.json or .atcourse)");
  const fs::path file = args.positional()[1];
  auto session = LearningSession::open(args.db());
  if (!session) return reportError("course import: " + session.error().message);
  if (file.extension() == ".json") {
    if (args.has("volume")) return reportError("course import: --volume applies to packages (.atcourse), not to course files");
    auto course = lessons::loadCourseJson(file);
    if (!course) return reportError(course.error().message);
    auto stored = saveCourse(**session, *course, fs::absolute(file).string());
    if (!stored) return reportError(stored.error().message);
    terminalPrintf("course '%s' version %d: %s\n", course->id.c_str(), course->version, db::toString(*stored));
    return 0;
  }
  CourseImportRequest request;
  request.package = file;
  request.volumePath = args.valueOr("volume", "");
  auto report = importCoursePackage(**session, request);
  if (!report) return reportError(report.error().message);
  terminalPrintf("course '%s' (%s) version %d: %s\n", report->courseId.c_str(), rowCell(report->courseTitle).c_str(), report->version,
              db::toString(report->outcome));
  terminalPrintf("  dataset '%s': %s%s\n", report->datasetId.c_str(), toString(report->dataset),
              report->datasetFolder.empty() ? "" : (" into " + report->datasetFolder.string()).c_str());
  std::string presets;
  for (const std::string& key : report->presetsStored) presets += (presets.empty() ? " (" : ", ") + key;
  terminalPrintf("  presets: %zu stored for this course only%s\n", report->presetsStored.size(),
              presets.empty() ? "" : (presets + ")").c_str());
  return 0;
}

int runExport(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("course export: give one course ID (see `anatomy-tutor course list`)");
  const auto out = args.value("out");
  if (!out) return reportError("course export: --out F.atcourse is required");
  if (args.has("note") && !args.has("reference-volume")) return reportError("course export: --note goes with --reference-volume");
  auto session = LearningSession::open(args.db());
  if (!session) return reportError("course export: " + session.error().message);
  CourseExportRequest request;
  request.courseId = args.positional()[1];
  request.out = *out;
  request.referenceVolume = args.has("reference-volume");
  request.referenceNote = args.valueOr("note", "");
  auto report = exportCourse(**session, render::PresetLibrary(defaultPresetsDir()), request);
  if (!report) return reportError("course export: " + report.error().message);
  terminalPrintf("%s: course '%s' on '%s' (%s volume), %zu presets, %zu structures, %ju bytes\n", report->file.string().c_str(),
              request.courseId.c_str(), report->datasetId.c_str(), package::toString(report->source), report->presets,
              report->structures, report->bytes);
  return 0;
}

}  // namespace

int runCourse(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"dataset", "title", "out", "volume", "note"}, {"reference-volume", "skip-view-check"});
  if (!args) return reportError("course: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kCourseHelp);
    return 0;
  }
  if (args->positional().empty()) return reportError("course: give a subcommand: new, validate, import, export or list (see --help)");
  const std::string& verb = args->positional()[0];
  if (verb == "new") return runNew(*args);
  if (verb == "validate") return runValidate(*args);
  if (verb == "import") return runImportFile(*args);
  if (verb == "export") return runExport(*args);
  if (verb == "list") {
    Argv rest;
    if (auto db = args->db()) rest = {"--db", *db};
    return runCourses(rest);
  }
  return reportError("course: unknown subcommand '" + verb + "' (new, validate, import, export, list)");
}

}  // namespace at::app
