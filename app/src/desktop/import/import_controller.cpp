#include "import/import_controller.h"

#include <array>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <vector>

#include "core/strings.h"

namespace at::app {

namespace {

using json = nlohmann::json;

constexpr std::array<ImportStage, 6> kStages = {ImportStage::Checking,      ImportStage::LoadingVolume,
                                                ImportStage::LoadingLabels, ImportStage::CheckingAlignment,
                                                ImportStage::Checksums,     ImportStage::Storing};
// Share of the whole import each stage takes on the progress bar (loading dominates).
constexpr std::array<float, 6> kStageWeight = {0.02f, 0.5f, 0.25f, 0.05f, 0.15f, 0.03f};

// What the loaders count (ImageLoadOptions::progress) for `path`: slices of a DICOM series,
// data files of an NRRD (a detached header may name many), bytes otherwise (shown as a percentage).
std::string unitsText(const std::string& path, std::size_t done, std::size_t total) {
  std::error_code ec;
  char text[64];
  if (std::filesystem::is_directory(path, ec) || str::endsWith(path, ".dcm"))
    std::snprintf(text, sizeof text, "slice %zu of %zu", done, total);
  else if (str::endsWith(path, ".nhdr") || str::endsWith(path, ".nrrd"))
    std::snprintf(text, sizeof text, "file %zu of %zu", done, total);
  else
    std::snprintf(text, sizeof text, "%.0f%%", 100.0 * double(done) / double(total));
  return text;
}

}  // namespace

std::optional<ImportStage> parseImportStage(const std::string& name) {
  for (ImportStage s : kStages)
    if (name == toString(s)) return s;
  return std::nullopt;
}

std::string importStageNames() {
  std::vector<std::string> names;
  for (ImportStage s : kStages) names.push_back("\"" + std::string(toString(s)) + "\"");
  return str::join(names, ", ");
}

struct ImportController::Job {
  ImportRequest request;
  std::optional<ImportStage> cancelAt;  // cancel as this stage starts (set before the thread)
  std::atomic<bool> cancel{false};

  std::mutex mutex;                     // guards what follows
  std::vector<ImportStage> started;     // stages started and not yet reported
  std::optional<ImportStage> lastStarted;
  ImportStage stage = ImportStage::Checking;
  std::size_t done = 0, total = 0;
  std::optional<Result<ImportedDataset>> result;
};

ImportController::ImportController(db::Database& database, EventSink events, MessageSink messages)
    : database_(database), events_(std::move(events)), messages_(std::move(messages)) {}

ImportController::~ImportController() {
  if (job_) job_->cancel = true;
  if (thread_.joinable()) thread_.join();
}

bool ImportController::running() const {
  if (!job_) return false;
  std::lock_guard lock(job_->mutex);
  return !job_->result.has_value();
}

Status ImportController::start(const ImportRequest& request, std::optional<ImportStage> cancelAt) {
  if (running()) return fail("an import is running; cancel it or wait for it to finish");
  if (thread_.joinable()) thread_.join();
  auto job = std::make_shared<Job>();
  job->request = request;
  job->cancelAt = cancelAt;
  job_ = job;
  reported_ = false;
  lastProgress_.clear();
  status_.clear();
  failed_ = false;
  imported_.reset();
  openRequested_ = false;
  events_({{"event", "import_started"}, {"name", request.name}, {"volume", request.volumePath}});
  db::Database* database = &database_;
  thread_ = std::jthread([job, database] {
    ImportControl control;
    control.cancel = &job->cancel;
    control.progress = [&job](ImportStage stage, std::size_t done, std::size_t total) {
      const bool starting = done == 0 && total == 0;
      if (starting && job->cancelAt == stage) job->cancel = true;
      std::lock_guard lock(job->mutex);
      if (starting && job->lastStarted != stage) {  // a stage may announce itself more than once
        job->lastStarted = stage;
        job->started.push_back(stage);
      }
      job->stage = stage;
      job->done = done;
      job->total = total;
    };
    auto result = importDataset(*database, job->request, control);
    std::lock_guard lock(job->mutex);
    job->result = std::move(result);
  });
  return {};
}

void ImportController::cancel() {
  if (job_ && running()) job_->cancel = true;
}

std::optional<ImportController::Progress> ImportController::progress() const {
  if (!running()) return std::nullopt;
  Progress p;
  p.cancelling = job_->cancel.load();
  {
    std::lock_guard lock(job_->mutex);
    p.stage = job_->stage;
    p.done = job_->done;
    p.total = job_->total;
  }
  std::size_t i = 0;
  for (; i < kStages.size() && kStages[i] != p.stage; ++i) p.fraction += kStageWeight[i];
  if (i < kStages.size()) p.fraction += kStageWeight[i] * (p.total > 0 ? float(double(p.done) / double(p.total)) : 0.0f);
  const std::string stage = toString(p.stage);
  if (p.cancelling)
    p.text = "cancelling (" + stage + ")...";
  else if (p.total > 0)
    p.text = stage + ": " +
             unitsText(p.stage == ImportStage::LoadingLabels ? job_->request.labelsPath : job_->request.volumePath, p.done, p.total);
  else
    p.text = stage + "...";
  return p;
}

std::optional<Dataset> ImportController::takeDatasetToOpen() {
  if (!openRequested_ || !imported_) return std::nullopt;
  openRequested_ = false;
  std::optional<Dataset> out = std::move(imported_);
  imported_.reset();
  return out;
}

void ImportController::openFailed(const std::string& why) {
  failed_ = true;
  status_ = why;
  events_({{"event", "import_open_failed"}, {"message", why}});
}

void ImportController::poll() {
  if (!job_ || reported_) return;
  std::unique_lock lock(job_->mutex);
  for (ImportStage s : job_->started) events_({{"event", "import_progress"}, {"stage", toString(s)}, {"done", 0}, {"total", 0}});
  job_->started.clear();
  if (job_->total > 0) {  // the loaders' units within a stage, reported as they change between frames
    const std::string key = std::string(toString(job_->stage)) + " " + std::to_string(job_->done) + "/" +
                            std::to_string(job_->total);
    if (key != lastProgress_) {
      lastProgress_ = key;
      events_({{"event", "import_progress"}, {"stage", toString(job_->stage)}, {"done", job_->done},
               {"total", job_->total}});
    }
  }
  if (!job_->result) return;
  Result<ImportedDataset> result = std::move(*job_->result);
  lock.unlock();
  reported_ = true;
  if (thread_.joinable()) thread_.join();
  const std::string& name = job_->request.name;
  if (result) {
    const Geometry& g = result->record.geometry;
    char text[512];
    std::snprintf(text, sizeof text, "Imported '%s': %s voxels, %.3g x %.3g x %.3g mm, %s; %zu structures.",
                  name.c_str(), g.dims.toString().c_str(), g.spacingMm[0], g.spacingMm[1], g.spacingMm[2],
                  result->record.orientation.c_str(), result->dataset.structures.size());
    status_ = text;
    const IntensityModel& values = result->dataset.intensity;
    status_ += std::string(" Values: ") + (values.hounsfield() ? "CT in HU" : "plain intensities") + " (" + values.reason + ").";
    for (const std::string& warning : result->dataset.provenance.warnings) status_ += " Warning: " + warning + ".";
    if (!result->emptyStructures.empty())
      status_ += " " + std::to_string(result->emptyStructures.size()) + " named structures have no voxel on the grid.";
    events_({{"event", "import_done"}, {"name", name}, {"structures", result->dataset.structures.size()},
             {"dims", {g.dims.x, g.dims.y, g.dims.z}}, {"empty_structures", result->emptyStructures},
             {"warnings", result->dataset.provenance.warnings},
             {"values", result->dataset.intensity.hounsfield() ? "hu" : "plain"},
             {"values_reason", result->dataset.intensity.reason}});
    imported_ = std::move(result->dataset);
  } else if (result.error().kind == ErrorKind::Cancelled) {
    status_ = "Import of '" + name + "' cancelled; nothing was stored.";
    events_({{"event", "import_cancelled"}, {"name", name}});
  } else {
    failed_ = true;
    status_ = result.error().message;
    messages_("import: " + status_);
    events_({{"event", "import_failed"}, {"name", name}, {"message", status_}});
  }
}

}  // namespace at::app
