#include "view/frame_scheduler.h"

#include <algorithm>
#include <cmath>

namespace at::app {

using json = nlohmann::json;

double msBetween(Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double, std::milli>(b - a).count(); }

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double pos = p / 100.0 * double(values.size() - 1);
  const std::size_t lo = std::size_t(std::floor(pos)), hi = std::min(values.size() - 1, lo + 1);
  return values[lo] + (values[hi] - values[lo]) * (pos - double(lo));
}

// ---------------------------------------------------------------------------------------------
// FrameScheduler

FrameScheduler::FrameScheduler(double frameBudgetMs, double renderScale)
    : frameBudgetMs_(frameBudgetMs), renderScale_(renderScale) {}

void FrameScheduler::setViewPixels(int width, int height) {
  viewW_ = std::max(1, width);
  viewH_ = std::max(1, height);
}

RenderPlan FrameScheduler::planFor(int level) const {
  RenderPlan p;
  p.level = std::clamp(level, 0, kFullLevel);
  const QualityLevel q = kQualityLevels[p.level];
  p.width = std::max(16, int(std::lround(viewW_ * q.scale * renderScale_)));
  p.height = std::max(16, int(std::lround(viewH_ * q.scale * renderScale_)));
  p.stepFactor = q.stepFactor;
  p.shading = p.level == kFullLevel;
  p.jitter = p.level == kFullLevel;
  return p;
}

RenderPlan FrameScheduler::fullPlan(double scale) const {
  RenderPlan p = planFor(kFullLevel);
  p.width = std::max(16, int(std::lround(viewW_ * renderScale_ * scale)));
  p.height = std::max(16, int(std::lround(viewH_ * renderScale_ * scale)));
  return p;
}

double FrameScheduler::costMs(int level) const {
  const RenderPlan p = planFor(level);
  return msPerUnit_ * double(p.width) * double(p.height) / p.stepFactor;
}

double FrameScheduler::scaleForConvergence() const {
  if (!(msPerFullPixel_ > 0)) return 1;
  const RenderPlan full = planFor(kFullLevel);
  const double ms = msPerFullPixel_ * double(full.width) * double(full.height);
  return std::clamp(std::sqrt(kConvergeMs / ms), kMinFullScale, 1.0);
}

std::optional<RenderPlan> FrameScheduler::plan(std::uint64_t revision, std::uint64_t activity, Clock::time_point now,
                                               bool fullQuality) {
  if (activity != lastActivity_) {
    lastActivity_ = activity;
    lastChange_ = now;
  }
  if (!showing(revision)) {
    // Something changed: the finest whole-image level whose predicted cost fits the interaction
    // budget (the coarsest before anything was measured). A change that is not an interaction (a
    // field arriving, a script action) is handled alike and refined once the view rests.
    int level = 0;
    if (msPerUnit_ > 0)
      for (int l = kFullLevel; l >= 0; --l)
        if (costMs(l) <= kInteractionBudgetMs) {
          level = l;
          break;
        }
    interacting_ = true;
    lastChange_ = now;
    renderedRevision_ = revision;
    renderedLevel_ = level - 1;
    refining_ = false;
    refinedFraction_ = 0;
    settledAfterMs_.reset();
    return planFor(level);
  }
  if (renderedLevel_ >= kFullLevel) {
    interacting_ = false;
    return std::nullopt;  // at full quality: nothing new to show
  }
  if (msBetween(lastChange_, now) < kRestAfterMs) {
    interacting_ = true;
    return std::nullopt;  // the user is still moving: keep the image
  }
  interacting_ = false;
  if (!refining_) {
    refining_ = true;
    fullScale_ = fullQuality ? 1.0 : scaleForConvergence();
    restarts_ = fullQuality ? 2 : 0;
  }
  RenderPlan p = fullPlan(fullScale_);
  p.progressive = true;
  p.budgetMs = fullQuality ? 1e9 : refineBudgetMs();
  return p;
}

void FrameScheduler::rendered(const RenderPlan& plan, double ms) {
  const double units = double(plan.width) * double(plan.height) / plan.stepFactor;
  msPerUnit_ = msPerUnit_ > 0 ? 0.7 * msPerUnit_ + 0.3 * ms / units : ms / units;
  failures_ = 0;
  renderedLevel_ = plan.level;
  shownWidth_ = plan.width;
  if (plan.level >= kFullLevel) settledAfterMs_ = 0;  // the whole full level at once (a GPU)
}

bool FrameScheduler::refined(const RenderPlan& plan, const RefineReport& r, Clock::time_point now) {
  const double pixels = double(plan.width) * double(plan.height);
  failures_ = 0;
  if (r.fraction > 0 && r.imageMs > 0) msPerFullPixel_ = r.imageMs / (r.fraction * pixels);
  refinedFraction_ = r.complete ? 1.0 : r.fraction;
  if (plan.budgetMs > 0 && plan.budgetMs < 1e6) {
    const double over = std::max(1.0, r.callMs / plan.budgetMs);
    overshoot_ = 0.8 * overshoot_ + 0.2 * over;
  }
  if (restarts_ < 2 && !r.complete && r.fraction < 0.3 && msPerFullPixel_ > 0) {
    // Early in the image, at the cost measured on it: an image that would take far longer than
    // kConvergeMs starts over smaller (losing the rays cast so far, at most twice per rest).
    const double scale = scaleForConvergence();
    if (scale < 0.8 * fullScale_) {
      fullScale_ = scale;
      refinedFraction_ = 0;
      ++restarts_;
      return false;
    }
  }
  if (r.complete) {
    renderedLevel_ = kFullLevel;
    shownWidth_ = plan.width;
    settledAfterMs_ = msBetween(lastChange_, now);
    return true;
  }
  const int sharpness = r.displayable ? (plan.width + r.stride - 1) / r.stride : 0;
  if (!r.displayable || sharpness < shownWidth_) return false;
  shownWidth_ = sharpness;
  return true;
}

void FrameScheduler::frameTook(double frameMs, double renderMs) {
  const double other = std::max(0.0, frameMs - renderMs);
  otherMs_ = otherMs_ > 0 ? 0.8 * otherMs_ + 0.2 * other : other;
}

double FrameScheduler::refineBudgetMs() const {
  // Calls overrun what they are given by a measured factor (chunks are whole tiles, and a loaded
  // machine stretches them): ask for that much less.
  return std::clamp((0.85 * frameBudgetMs_ - otherMs_) / overshoot_, 0.1 * frameBudgetMs_,
                    kRefineShareOfFrame * frameBudgetMs_);
}

void FrameScheduler::failed() {
  if (renderedRevision_ != failedRevision_) {  // another view: its own retries
    failedRevision_ = renderedRevision_;
    failures_ = 0;
  }
  if (++failures_ <= kRetriesAfterFailure) renderedRevision_.reset();  // planned again from the start
  else renderedLevel_ = kFullLevel;
}

bool FrameScheduler::finished(std::uint64_t revision) const { return showing(revision) && renderedLevel_ >= kFullLevel; }

// ---------------------------------------------------------------------------------------------
// FrameRecorder

void FrameRecorder::start() {
  recording_ = true;
  recordingStart_ = Clock::now();
  frames_.clear();
  latencies_.clear();
  settles_.clear();
  settleScales_.clear();
}

void FrameRecorder::beginFrame() {
  inFrame_ = recording_;
  if (!inFrame_) return;
  frames_.push_back({});
  frames_.back().atMs = msBetween(recordingStart_, Clock::now());
}

void FrameRecorder::notePrepare(double prepareMs, double maskMs, double tableMs, double occupancyMs, int firstUses) {
  if (!inFrame_ || frames_.empty()) return;
  Frame& f = frames_.back();
  f.prepareMs += prepareMs;
  f.maskMs += maskMs;
  f.tableMs += tableMs;
  f.occupancyMs += occupancyMs;
  f.firstUses += firstUses;
}

void FrameRecorder::notePhases(const FramePhases& phases) {
  if (inFrame_ && !frames_.empty()) frames_.back().phases = phases;
}

void FrameRecorder::noteUpload(double ms) {
  if (inFrame_ && !frames_.empty()) frames_.back().uploadMs += ms;
}

void FrameRecorder::noteRender(int level, double ms) {
  if (!inFrame_ || frames_.empty()) return;
  frames_.back().level = level;
  frames_.back().renderMs = ms;
}

void FrameRecorder::noteRefine(double ms) {
  if (!inFrame_ || frames_.empty()) return;
  frames_.back().level = kFullLevel;
  frames_.back().renderMs = ms;
  frames_.back().refine = true;
}

void FrameRecorder::noteSettled(double ms, double scale) {
  if (!recording_) return;
  settles_.push_back(ms);
  settleScales_.push_back(scale);
}

void FrameRecorder::endFrame(double ms, bool interacting) {
  if (!inFrame_ || frames_.empty()) return;
  frames_.back().ms = ms;
  frames_.back().interacting = interacting;
  inFrame_ = false;
}

void FrameRecorder::frameShown(bool current, std::uint16_t label, Clock::time_point at) {
  if (!pendingHighlight_ || !current || label != pendingHighlight_->first) return;
  if (recording_) latencies_.push_back(msBetween(pendingHighlight_->second, at));
  pendingHighlight_.reset();
}

json FrameRecorder::report(const Context& context) const {
  std::vector<double> all, moving, rest, uploads, renders;
  std::vector<double> input, model, view, ui, prepare;
  std::map<int, int> perLevel;
  int overBudget = 0, refines = 0;
  json slow = json::array();
  constexpr std::size_t kSlowFramesListed = 24;
  const auto r1 = [](double v) { return std::round(v * 10) / 10; };
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    const Frame& f = frames_[i];
    if (f.uploadMs > 0) uploads.push_back(f.uploadMs);
    if (f.level >= 0) renders.push_back(f.renderMs);
    input.push_back(f.phases.inputMs);
    model.push_back(f.phases.modelMs);
    view.push_back(f.phases.viewMs);
    ui.push_back(f.phases.uiMs);
    prepare.push_back(f.prepareMs);
    if (f.ms > context.frameBudgetMs && slow.size() < kSlowFramesListed)
      slow.push_back({{"frame", i},         {"at_ms", r1(f.atMs)},          {"ms", r1(f.ms)},
                      {"input_ms", r1(f.phases.inputMs)}, {"model_ms", r1(f.phases.modelMs)},
                      {"upload_ms", r1(f.uploadMs)},     {"view_ms", r1(f.phases.viewMs)},
                      {"render_ms", r1(f.renderMs)},     {"prepare_ms", r1(f.prepareMs)},
                      {"mask_ms", r1(f.maskMs)},
                      {"table_ms", r1(f.tableMs)},       {"occupancy_ms", r1(f.occupancyMs)},
                      {"first_variant_uses", f.firstUses}, {"ui_ms", r1(f.phases.uiMs)},
                      {"level", f.level},                {"refine", f.refine}});
    if (f.ms > context.frameBudgetMs) ++overBudget;
    all.push_back(f.ms);
    (f.interacting ? moving : rest).push_back(f.ms);
    if (f.refine) ++refines;
    else perLevel[f.level]++;
  }
  const auto maxOf = [](const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); };
  json levels = json::object();
  for (const auto& [l, n] : perLevel) levels[l < 0 ? "reused" : std::to_string(l)] = n;
  if (refines) levels["refine"] = refines;
  return {{"event", "report"},
          {"frames", all.size()},
          {"frame_ms_p50", percentile(all, 50)},
          {"frame_ms_p99", percentile(all, 99)},
          {"frame_ms_max", maxOf(all)},
          {"moving_frames", moving.size()},
          {"moving_ms_p99", percentile(moving, 99)},
          {"rest_frames", rest.size()},
          {"rest_ms_p99", percentile(rest, 99)},
          {"frames_per_level", levels},
          {"field_uploads", uploads.size()},
          {"field_upload_ms_max", maxOf(uploads)},
          {"frame_budget_ms", context.frameBudgetMs},
          {"frames_over_budget", overBudget},
          {"phase_ms_p99", {{"input", percentile(input, 99)}, {"model", percentile(model, 99)},
                            {"view", percentile(view, 99)}, {"prepare", percentile(prepare, 99)},
                            {"ui", percentile(ui, 99)}}},
          {"phase_ms_max", {{"input", maxOf(input)}, {"model", maxOf(model)}, {"view", maxOf(view)},
                            {"prepare", maxOf(prepare)}, {"ui", maxOf(ui)}}},
          {"slow_frames", slow},
          {"renders", renders.size()},
          {"render_ms_p50", percentile(renders, 50)},
          {"render_ms_max", maxOf(renders)},
          {"settles", settles_.size()},
          {"settle_ms_p50", percentile(settles_, 50)},
          {"settle_ms_max", maxOf(settles_)},
          {"full_scale_min", settleScales_.empty() ? 0.0 : *std::min_element(settleScales_.begin(), settleScales_.end())},
          {"highlights", latencies_.size()},
          {"highlight_ms_p50", percentile(latencies_, 50)},
          {"highlight_ms_p99", percentile(latencies_, 99)},
          {"highlight_ms_max", maxOf(latencies_)},
          {"fields_cancelled", context.fieldsCancelled},
          {"window", context.window},
          {"gl", context.gl}};
}

}  // namespace at::app
