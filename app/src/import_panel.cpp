#include "import_panel.h"

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <vector>

#include <imgui.h>

namespace at::app {

namespace {

using json = nlohmann::json;

constexpr std::array<ImportStage, 6> kStages = {ImportStage::Checking,      ImportStage::LoadingVolume,
                                                ImportStage::LoadingLabels, ImportStage::CheckingAlignment,
                                                ImportStage::Checksums,     ImportStage::Storing};
// Share of the whole import each stage takes on the progress bar (loading dominates).
constexpr std::array<float, 6> kStageWeight = {0.02f, 0.5f, 0.25f, 0.05f, 0.15f, 0.03f};

std::optional<ImportStage> parseStage(const std::string& name) {
  for (ImportStage s : kStages)
    if (name == toString(s)) return s;
  return std::nullopt;
}

// What the loaders count (ImageLoadOptions::progress) for `path`: slices of a DICOM series,
// data files of an NRRD (a detached header may name many), bytes otherwise (shown as a percentage).
std::string unitsText(const std::string& path, std::size_t done, std::size_t total) {
  std::error_code ec;
  const auto ends = [&](const char* suffix) {
    const std::string s = suffix;
    return path.size() >= s.size() && path.compare(path.size() - s.size(), s.size(), s) == 0;
  };
  char text[64];
  if (std::filesystem::is_directory(path, ec) || ends(".dcm"))
    std::snprintf(text, sizeof text, "slice %zu of %zu", done, total);
  else if (ends(".nhdr") || ends(".nrrd"))
    std::snprintf(text, sizeof text, "file %zu of %zu", done, total);
  else
    std::snprintf(text, sizeof text, "%.0f%%", 100.0 * double(done) / double(total));
  return text;
}

std::string stageList() {
  std::string out;
  for (ImportStage s : kStages) out += (out.empty() ? "\"" : ", \"") + std::string(toString(s)) + "\"";
  return out;
}

}  // namespace

struct ImportPanel::Job {
  ImportRequest request;
  std::optional<ImportStage> cancelAt;  // scripted: cancel as this stage starts (set before the thread)
  std::atomic<bool> cancel{false};

  std::mutex mutex;                     // guards what follows
  std::vector<ImportStage> started;     // stages started and not yet reported
  std::optional<ImportStage> lastStarted;
  ImportStage stage = ImportStage::Checking;
  std::size_t done = 0, total = 0;
  std::optional<Result<ImportedDataset>> result;
};

ImportPanel::ImportPanel(db::Database& database, EventSink events, MessageSink messages)
    : database_(database), events_(std::move(events)), messages_(std::move(messages)) {}

ImportPanel::~ImportPanel() {
  if (job_) job_->cancel = true;
  if (thread_.joinable()) thread_.join();
}

bool ImportPanel::running() const {
  if (!job_) return false;
  std::lock_guard lock(job_->mutex);
  return !job_->result.has_value();
}

Status ImportPanel::start(const ImportRequest& request) { return launch(request, std::nullopt); }

Status ImportPanel::launch(const ImportRequest& request, std::optional<ImportStage> cancelAt) {
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

void ImportPanel::cancel() {
  if (job_ && running()) job_->cancel = true;
}

std::optional<Dataset> ImportPanel::takeDatasetToOpen() {
  if (!openRequested_ || !imported_) return std::nullopt;
  openRequested_ = false;
  std::optional<Dataset> out = std::move(imported_);
  imported_.reset();
  return out;
}

void ImportPanel::poll() {
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
    if (!result->emptyStructures.empty())
      status_ += " " + std::to_string(result->emptyStructures.size()) + " named structures have no voxel on the grid.";
    events_({{"event", "import_done"}, {"name", name}, {"structures", result->dataset.structures.size()},
             {"dims", {g.dims.x, g.dims.y, g.dims.z}}, {"empty_structures", result->emptyStructures}});
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

void ImportPanel::draw(float x, float y) {
  poll();
  if (open_) drawWindow(x, y);
}

void ImportPanel::drawWindow(float x, float y) {
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  const float width = ImGui::GetFontSize() * 48;
  ImGui::SetNextWindowSizeConstraints(ImVec2(width, 0), ImVec2(width, 10000));
  if (!ImGui::Begin("Import dataset", &open_, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::End();
    return;
  }
  const bool busy = running();
  ImGui::BeginDisabled(busy);
  ImGui::PushItemWidth(-ImGui::GetFontSize() * 4.5f);
  ImGui::InputTextWithHint("volume", "DICOM folder, .nii, .nii.gz, .nrrd, .nhdr or .inv3", volume_, sizeof volume_);
  ImGui::InputTextWithHint("labels", "optional: label map (those formats or DICOM SEG)", labels_, sizeof labels_);
  ImGui::InputTextWithHint("names", "optional: JSON {\"1\": \"spleen\", ...}", names_, sizeof names_);
  ImGui::InputTextWithHint("name", "what the dataset will be called", name_, sizeof name_);
  ImGui::InputText("species", species_, sizeof species_);
  ImGui::PopItemWidth();
  if (ImGui::Button("Import")) {
    ImportRequest request;
    request.volumePath = volume_;
    request.labelsPath = labels_;
    request.namesPath = names_;
    request.name = name_;
    request.species = species_;
    if (auto st = start(request); !st) {
      status_ = st.error().message;
      failed_ = true;
    }
  }
  ImGui::EndDisabled();

  if (busy) {
    ImportStage stage;
    std::size_t done, total;
    bool cancelling = job_->cancel.load();
    {
      std::lock_guard lock(job_->mutex);
      stage = job_->stage;
      done = job_->done;
      total = job_->total;
    }
    float fraction = 0;
    std::size_t i = 0;
    for (; i < kStages.size() && kStages[i] != stage; ++i) fraction += kStageWeight[i];
    const float within = total > 0 ? float(double(done) / double(total)) : 0.0f;
    if (i < kStages.size()) fraction += kStageWeight[i] * within;
    char overlay[128];
    if (cancelling)
      std::snprintf(overlay, sizeof overlay, "cancelling (%s)...", toString(stage));
    else if (total > 0)
      std::snprintf(overlay, sizeof overlay, "%s: %s", toString(stage),
                    unitsText(stage == ImportStage::LoadingLabels ? job_->request.labelsPath : job_->request.volumePath,
                              done, total)
                        .c_str());
    else
      std::snprintf(overlay, sizeof overlay, "%s...", toString(stage));
    ImGui::ProgressBar(fraction, ImVec2(-90, 0), overlay);
    ImGui::SameLine();
    ImGui::BeginDisabled(cancelling);
    if (ImGui::Button("Cancel")) cancel();
    ImGui::EndDisabled();
  } else if (!status_.empty()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(failed_ ? ImVec4(1, 0.5f, 0.4f, 1) : ImVec4(0.6f, 1, 0.6f, 1), "%s", status_.c_str());
    ImGui::PopTextWrapPos();
  }
  if (!busy && imported_ && ImGui::Button("Open in explore view")) openRequested_ = true;
  ImGui::End();
}

std::optional<Result<bool>> ImportPanel::scriptAction(const std::string& what, const json& a) {
  using R = Result<bool>;
  if (what == "import") {
    if (!scriptImporting_) {
      ImportRequest request;
      request.volumePath = a.at("volume").get<std::string>();
      request.labelsPath = a.value("labels", "");
      request.namesPath = a.value("names", "");
      request.name = a.at("name").get<std::string>();
      request.species = a.value("species", "human");
      std::optional<ImportStage> cancelAt;
      if (a.contains("cancel_at")) {
        cancelAt = parseStage(a.at("cancel_at").get<std::string>());
        if (!cancelAt) return R(fail("ui script: import: \"cancel_at\" must be one of " + stageList()));
      }
      if (auto st = launch(request, cancelAt); !st) return R(tl::unexpected(st.error()));
      // Shown as a user would see it: the window open on the form that started it.
      open_ = true;
      std::snprintf(volume_, sizeof volume_, "%s", request.volumePath.c_str());
      std::snprintf(labels_, sizeof labels_, "%s", request.labelsPath.c_str());
      std::snprintf(names_, sizeof names_, "%s", request.namesPath.c_str());
      std::snprintf(name_, sizeof name_, "%s", request.name.c_str());
      std::snprintf(species_, sizeof species_, "%s", request.species.c_str());
      if (!a.value("wait", true)) return R(true);
      scriptImporting_ = true;
      return R(false);
    }
    if (!reported_) return R(false);
    scriptImporting_ = false;
    return R(true);
  }
  if (what == "cancel_import") {
    cancel();
    return R(!job_ || reported_);  // done once the outcome (cancelled, or done if it was too late) is out
  }
  if (what == "open_imported") {
    if (!scriptOpening_) {
      if (!imported_) return R(fail("ui script: open_imported: no successful import to open"));
      openRequested_ = true;
      scriptOpening_ = true;
      return R(false);
    }
    if (openRequested_) return R(false);  // the app takes the dataset in its next frame
    scriptOpening_ = false;
    return R(true);
  }
  return std::nullopt;
}

}  // namespace at::app
