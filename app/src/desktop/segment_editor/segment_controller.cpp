#include "segment_editor/segment_controller.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>
#include <cmath>

#include "core/strings.h"
#include "label_output.h"
#include "scan_catalogue.h"
#include "segment/local_threshold.h"
#include "volume/label_writers.h"
#include "volume/slice_image.h"
#include "wdt/label_growth.h"

namespace at::app {

namespace {

std::uint8_t toByte(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  const double srgb = linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
  return std::uint8_t(std::lround(255 * srgb));
}

}  // namespace

struct SegmentController::GrowJob {
  std::atomic<bool> cancel{false};
  std::atomic<bool> finished{false};
  std::optional<Result<GrowthStats>> result;  // written by the worker before `finished`
  std::size_t seedCount = 0;
  std::chrono::steady_clock::time_point start;
  std::jthread thread;  // last: joined before the members above go
};

SegmentController::SegmentController(db::Database& database, EventSink events)
    : database_(database), events_(std::move(events)) {}

SegmentController::~SegmentController() { stopGrowth(); }

void SegmentController::attach(const Dataset& dataset, const Volume* grown) {
  stopGrowth();  // it grows the editor and volume being replaced
  growError_.reset();
  dataset_ = &dataset;
  grown_ = grown ? grown : &dataset.volume;
  const LabelMap start = dataset.labels.empty() ? LabelMap(dataset.volume.geometry, 0) : dataset.labels;
  editor_ = std::make_unique<segment::LabelEditor>(start, dataset.structures);
  seeds_.clear();
  growRanges_.clear();
  current_ = 0;
  axis_ = 2;
  index_ = dataset.volume.dims().z / 2;
  const Vec3& spacing = dataset.volume.geometry.spacingMm;
  const double scale = fineVoxelScale(std::max({spacing[0], spacing[1], spacing[2]}));
  brushMm *= scale / brushScale_;
  brushScale_ = scale;
  grey_.reset(dataset.intensity);
  status_.clear();
  grownOnce_ = false;
  defaults_ = segment::defaultGrowthSettings(*grown_, dataset.intensity);
  settings_ = {segment::basePerVoxelOf(defaults_.params.baseCost, defaults_.voxelMm), defaults_.windowValues,
               defaults_.params.smoothingVoxels, false, defaults_.boneRangeValues};
  ++revision_;
  // An imported dataset's review states (a failed read is said; the states start as not started);
  // a built-in scan's (the skull) are the ones its shipped catalogue records.
  review_.clear();
  auto record = db::findDataset(database_, dataset.id);
  if (record && *record) {
    if (auto stored = db::datasetReviewStates(database_, (*record)->id)) review_ = std::move(*stored);
    else record = tl::unexpected(stored.error());
  } else if (record) {
    const auto catalogueFile = catalogueFileFor(dataset.id);
    std::error_code missing;
    if (std::filesystem::exists(catalogueFile, missing)) {
      if (auto catalogue = loadStructureCatalogue(catalogueFile)) {
        for (const CatalogueEntry& entry : catalogue->structures)
          if (auto state = db::reviewStateNamed(entry.reviewState)) review_[entry.id] = *state;
      } else {
        status_ = "review states: " + catalogue.error().message;
      }
    }
  }
  if (!record) status_ = "review states: " + record.error().message;
}

Status SegmentController::requireDataset() const {
  if (!dataset_) return fail(ErrorKind::Unavailable, "segment editor: no dataset is open");
  return {};
}

const std::vector<Structure>& SegmentController::structures() const {
  static const std::vector<Structure> none;
  return editor_ ? editor_->structures() : none;
}

const LabelMap& SegmentController::labels() const {
  static const LabelMap none;
  return editor_ ? editor_->labels() : none;
}

Result<std::uint16_t> SegmentController::addLabel(const std::string& name) {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  if (str::lower(str::trim(name)) == "background") return fail(ErrorKind::Conflict, "'background' is label 0 already");
  auto label = editor_->addStructure(str::trim(name));
  if (!label) return label;
  current_ = *label;
  ++revision_;
  ++labelsRevision_;
  return label;
}

Status SegmentController::setSystem(std::uint16_t label, const std::string& system) {
  if (auto ok = requireDataset(); !ok) return ok;
  if (auto ok = editor_->setSystem(label, system); !ok) return ok;
  ++revision_;
  ++labelsRevision_;
  return {};
}

Status SegmentController::setCurrentLabel(std::uint16_t label) {
  if (auto ok = requireDataset(); !ok) return ok;
  if (label != 0 && std::none_of(structures().begin(), structures().end(), [&](const Structure& s) { return s.label == label; }))
    return fail(ErrorKind::NotFound, "segment editor: no label " + std::to_string(label));
  current_ = label;
  return {};
}

Result<std::uint16_t> SegmentController::labelNamed(const std::string& name) const {
  if (str::lower(name) == "background") return std::uint16_t(0);
  const std::string wanted = str::lower(name);
  for (const Structure& s : structures())
    if (str::lower(s.id) == wanted || str::lower(s.displayName) == wanted) return s.label;
  std::vector<std::string> names{"background"};
  for (const Structure& s : structures()) names.push_back(s.id);
  return fail(ErrorKind::NotFound, "segment editor: no label '" + name + "' (labels: " + str::join(names, ", ") + ")");
}

int SegmentController::sliceCount() const {
  if (!dataset_) return 0;
  const Dims d = dataset_->volume.dims();
  return axis_ == 0 ? d.x : axis_ == 1 ? d.y : d.z;
}

Status SegmentController::showAxis(int axis) {
  if (auto ok = requireDataset(); !ok) return ok;
  const Dims d = dataset_->volume.dims();
  if (axis < 0 || axis > 2) return setSlice(axis, 0);
  return setSlice(axis, (axis == 0 ? d.x : axis == 1 ? d.y : d.z) / 2);
}

SliceLayout SegmentController::sliceLayout() const {
  const Mat3 direction = dataset_ ? dataset_->volume.geometry.direction : Mat3::identity();
  for (PatientPlane plane : {PatientPlane::Sagittal, PatientPlane::Coronal, PatientPlane::Axial}) {
    const SliceLayout layout = patientSliceLayout(direction, plane);
    if (layout.sliceAxis == axis_) return layout;
  }
  return voxelSliceLayout(axis_, direction);  // not reached: the planes take the three axes
}

int SegmentController::axisOfPlane(PatientPlane plane) const {
  return patientSliceLayout(dataset_ ? dataset_->volume.geometry.direction : Mat3::identity(), plane).sliceAxis;
}

std::array<double, 2> SegmentController::slicePixelMm() const {
  if (!dataset_) return {1, 1};
  const auto& sp = dataset_->volume.geometry.spacingMm;
  const SliceLayout layout = sliceLayout();
  return {sp[std::size_t(layout.columnAxis)], sp[std::size_t(layout.rowAxis)]};
}

Status SegmentController::setSlice(int axis, int index) {
  if (auto ok = requireDataset(); !ok) return ok;
  if (axis < 0 || axis > 2) return fail("segment editor: slice axis must be 0, 1 or 2 (x, y, z), not " + std::to_string(axis));
  const Dims d = dataset_->volume.dims();
  const int count = axis == 0 ? d.x : axis == 1 ? d.y : d.z;
  if (index < 0 || index >= count)
    return fail("segment editor: slice " + std::to_string(index) + " is outside 0 … " + std::to_string(count - 1));
  if (axis != axis_ || index != index_) ++revision_;
  axis_ = axis;
  index_ = index;
  return {};
}

Result<RgbImage> SegmentController::sliceImage(int scale, double labelAlpha) const {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  SliceRequest request;
  request.layout = sliceLayout();
  request.index = index_;
  request.scale = scale;
  request.labelAlpha = labelAlpha;
  grey_.applyTo(request);
  auto image = renderSlice(dataset_->volume, &editor_->labels(), editor_->structures(), request);
  if (!image || seeds_.empty()) return image;
  // Seeds on this slice, opaque, where the layout puts their voxels.
  const Dims d = dataset_->volume.dims();
  const SliceLayout& layout = *request.layout;
  const int extent[3] = {d.x, d.y, d.z};
  for (const auto& [index, label] : seeds_) {
    const int ijk[3] = {int(index % std::size_t(d.x)), int(index / std::size_t(d.x) % std::size_t(d.y)),
                        int(index / (std::size_t(d.x) * std::size_t(d.y)))};
    if (ijk[axis_] != index_) continue;
    std::array<std::uint8_t, 3> colour{255, 255, 255};
    for (const Structure& s : editor_->structures())
      if (s.label == label) colour = {toByte(s.colour[0]), toByte(s.colour[1]), toByte(s.colour[2])};
    const int u = ijk[layout.columnAxis], v = ijk[layout.rowAxis];
    const int col = layout.columnReversed ? extent[layout.columnAxis] - 1 - u : u;
    const int row = layout.rowReversed ? extent[layout.rowAxis] - 1 - v : v;
    for (int dy = 0; dy < scale; ++dy)
      for (int dx = 0; dx < scale; ++dx) std::copy(colour.begin(), colour.end(), image->pixel(col * scale + dx, row * scale + dy));
  }
  return image;
}

void SegmentController::dragWindow(double dx, double dy) {
  if (grey_.drag(dx, dy)) ++revision_;
}

std::optional<std::array<int, 3>> SegmentController::voxelAtPixel(int scale, double x, double y) const {
  if (!dataset_) return std::nullopt;
  SliceRequest request;
  request.layout = sliceLayout();
  request.index = index_;
  request.scale = scale;
  return sliceVoxelAt(dataset_->volume.dims(), request, x, y);
}

Result<std::size_t> SegmentController::paintSeeds(const std::array<int, 3>& voxel) {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  const Geometry& g = dataset_->volume.geometry;
  const Dims d = g.dims;
  if (!d.contains(voxel[0], voxel[1], voxel[2]))
    return fail("segment editor: voxel (" + std::to_string(voxel[0]) + ", " + std::to_string(voxel[1]) + ", " +
                std::to_string(voxel[2]) + ") is outside the volume (" + d.toString() + ")");
  const double r = std::max(0.0, brushMm);
  if (seedRange) {
    auto region = segment::localThresholdRegion(*grown_, dataset_->intensity, voxel, r, (*seedRange)[0],
                                                (*seedRange)[1]);
    if (!region) return fail("segment editor: seeds in range: " + region.error().message);
    for (std::size_t v : *region) seeds_[v] = current_;
    ++revision_;
    return region->size();
  }
  int reach[3];
  for (int a = 0; a < 3; ++a) reach[a] = int(std::floor(r / g.spacingMm[std::size_t(a)]));
  std::size_t painted = 0;
  for (int k = std::max(0, voxel[2] - reach[2]); k <= std::min(d.z - 1, voxel[2] + reach[2]); ++k)
    for (int j = std::max(0, voxel[1] - reach[1]); j <= std::min(d.y - 1, voxel[1] + reach[1]); ++j)
      for (int i = std::max(0, voxel[0] - reach[0]); i <= std::min(d.x - 1, voxel[0] + reach[0]); ++i) {
        const double dx = (i - voxel[0]) * g.spacingMm[0], dy = (j - voxel[1]) * g.spacingMm[1],
                     dz = (k - voxel[2]) * g.spacingMm[2];
        if (dx * dx + dy * dy + dz * dz > r * r + 1e-9) continue;
        seeds_[d.index(i, j, k)] = current_;
        ++painted;
      }
  ++revision_;
  return painted;
}

void SegmentController::clearSeeds() {
  seeds_.clear();
  ++revision_;
}

std::map<std::uint16_t, std::size_t> SegmentController::seedsPerLabel() const {
  std::map<std::uint16_t, std::size_t> out;
  for (const auto& [index, label] : seeds_) ++out[label];
  return out;
}

Status SegmentController::grow() {
  if (auto ok = requireDataset(); !ok) return ok;
  const auto perLabel = seedsPerLabel();
  if (perLabel.size() < 2) {
    const std::string only = perLabel.empty() ? "no label has seeds"
                                              : "only label " + std::to_string(perLabel.begin()->first) + " has seeds";
    return fail("segment editor: " + only + "; grow from seeds needs seeds of two or more labels (background included)");
  }
  growError_.reset();
  if (job_) {  // latest wins: the running growth stops between rounds, then these seeds grow
    job_->cancel = true;
    growAgain_ = true;
    status_ = "growing again with the latest seeds...";
    return {};
  }
  return startGrowth();
}

Status SegmentController::startGrowth() {
  growAgain_ = false;
  if (seedsPerLabel().size() < 2) return fail("segment editor: grow from seeds needs seeds of two or more labels");
  std::vector<GrowthSeed> seeds;
  seeds.reserve(seeds_.size());
  for (const auto& [index, label] : seeds_) seeds.push_back({index, label});
  const GrowthParams params = growthParams();
  segment::LabelRanges ranges = labelRanges();
  grownOnce_ = true;
  auto job = std::make_unique<GrowJob>();
  job->seedCount = seeds.size();
  job->start = std::chrono::steady_clock::now();
  GrowJob* j = job.get();
  segment::LabelEditor* editor = editor_.get();
  const Volume* volume = grown_;
  job->thread = std::jthread([j, editor, volume, seeds = std::move(seeds), params, ranges = std::move(ranges)] {
    WdtControl control;
    control.cancel = &j->cancel;
    j->result = editor->computeGrowth(*volume, seeds, params, control, ranges);
    j->finished.store(true, std::memory_order_release);
  });
  job_ = std::move(job);
  status_ = "growing from seeds...";
  events_({{"event", "segment_growing"}, {"seeds", job_->seedCount}});
  return {};
}

void SegmentController::stopGrowth() {
  if (!job_) return;
  job_->cancel = true;
  job_.reset();  // joins the worker
  growAgain_ = false;
}

void SegmentController::poll() {
  if (!job_ || !job_->finished.load(std::memory_order_acquire)) return;
  std::unique_ptr<GrowJob> job = std::move(job_);
  job->thread.join();
  if (growAgain_) {  // the seeds changed meanwhile: only the latest growth is applied
    if (auto st = startGrowth(); !st) growError_ = st.error();
    return;
  }
  const Result<GrowthStats>& stats = *job->result;
  if (!stats) {
    growError_ = stats.error();
    status_.clear();
    events_({{"event", "segment_grow_failed"}, {"message", stats.error().message}});
    return;
  }
  auto summary = editor_->commitGrowth(job->seedCount);
  if (!summary) {
    growError_ = summary.error();
    return;
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - job->start).count();
  edited("segment_grown", "grow", *summary, {{"ms", ms}, {"device", stats->device}, {"incremental", stats->incremental}});
  status_ = summary->description + " (" + std::to_string(int(std::lround(ms))) + " ms on " + stats->device + ")";
}

void SegmentController::edited(const std::string& kind, const std::string& tool, const segment::EditSummary& summary,
                               nlohmann::json extra, bool countVoxels) {
  ++revision_;
  ++labelsRevision_;
  status_ = summary.description;
  nlohmann::json e = {{"event", kind}, {"tool", tool}, {"changed", summary.changed}};
  if (countVoxels) {
    std::vector<std::size_t> perValue(65536, 0);
    for (std::uint16_t v : editor_->labels().voxels) ++perValue[v];
    nlohmann::json counts = nlohmann::json::object();
    for (const Structure& s : editor_->structures()) counts[s.id] = perValue[s.label];
    e["voxels"] = std::move(counts);
  }
  e.update(extra);
  events_(std::move(e));
}

Result<std::string> SegmentController::undo() { return stepHistory(false); }
Result<std::string> SegmentController::redo() { return stepHistory(true); }

Result<std::string> SegmentController::stepHistory(bool forward) {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  auto stepped = forward ? editor_->redo() : editor_->undo();
  if (!stepped) return stepped;
  ++revision_;
  ++labelsRevision_;
  // A structure the step removed (an undone "add") is no longer a label to paint.
  if (std::none_of(structures().begin(), structures().end(), [&](const Structure& s) { return s.label == current_; }))
    current_ = 0;
  status_ = (forward ? "redone: " : "undone: ") + *stepped;
  events_({{"event", forward ? "segment_redone" : "segment_undone"}, {"edit", *stepped}});
  return stepped;
}

Result<std::string> SegmentController::saveToStore() {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  db::ReviewStates review;  // of the structures saved
  for (const Structure& s : editor_->structures()) review[s.id] = reviewState(s.label);
  auto saved = storeDatasetLabels(database_, dataset_->id, editor_->labels(), editor_->structures(), &review);
  if (!saved) return saved;
  status_ = "saved into the dataset store: " + *saved;
  events_({{"event", "segment_saved"}, {"store", true}, {"path", *saved}});
  return saved;
}

Status SegmentController::exportLabels(const std::string& path, const std::string& namesPath) {
  if (auto ok = requireDataset(); !ok) return ok;
  if (auto ok = writeLabelsFile(path, editor_->labels(), editor_->structures()); !ok) return ok;
  if (!namesPath.empty())
    if (auto ok = writeLabelNames(namesPath, editor_->structures()); !ok) return ok;
  status_ = "exported " + path + (namesPath.empty() ? "" : " and " + namesPath);
  events_({{"event", "segment_saved"}, {"store", false}, {"path", path}});
  return {};
}

}  // namespace at::app
