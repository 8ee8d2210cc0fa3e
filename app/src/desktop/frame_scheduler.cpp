#include "frame_scheduler.h"

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

double FrameScheduler::costMs(int level) const {
  const RenderPlan p = planFor(level);
  return msPerUnit_ * double(p.width) * double(p.height) / p.stepFactor;
}

std::optional<RenderPlan> FrameScheduler::plan(std::uint64_t revision, std::uint64_t activity, Clock::time_point now,
                                               bool fullAtRest) {
  if (activity != lastActivity_) {
    lastActivity_ = activity;
    lastChange_ = now;
  }
  if (!showing(revision)) {
    // Something changed: start at the finest level whose predicted cost fits the interaction
    // budget. A change that is not an interaction (a field arriving, a script action) after a
    // rest still starts coarse and is refined over the next frames.
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
  } else if (renderedLevel_ >= kFullLevel || msBetween(lastChange_, now) < kRestAfterMs) {
    interacting_ = renderedLevel_ < kFullLevel && msBetween(lastChange_, now) < kRestAfterMs;
    return std::nullopt;  // nothing new to show, or the user is still moving: keep the image
  } else {
    interacting_ = false;
    if (!fullAtRest && msPerUnit_ > 0 && costMs(renderedLevel_ + 1) > frameBudgetMs_) {
      restCapped_ = true;
      return std::nullopt;
    }
  }
  restCapped_ = false;
  int level = std::min(kFullLevel, renderedLevel_ + 1);
  if (!interacting_ && msPerUnit_ > 0)  // at rest: skip levels that would be cheap but still coarse
    while (level < kFullLevel && costMs(level + 1) <= kRefineBudgetMs) ++level;
  return planFor(level);
}

void FrameScheduler::rendered(const RenderPlan& plan, double ms) {
  const double units = double(plan.width) * double(plan.height) / plan.stepFactor;
  msPerUnit_ = msPerUnit_ > 0 ? 0.7 * msPerUnit_ + 0.3 * ms / units : ms / units;
  renderedLevel_ = plan.level;
}

void FrameScheduler::failed() { renderedLevel_ = kFullLevel; }

bool FrameScheduler::finished(std::uint64_t revision) const {
  return showing(revision) && (renderedLevel_ >= kFullLevel || restCapped_);
}

// ---------------------------------------------------------------------------------------------
// FrameRecorder

void FrameRecorder::start() {
  recording_ = true;
  frames_.clear();
  latencies_.clear();
}

void FrameRecorder::beginFrame() {
  inFrame_ = recording_;
  if (inFrame_) frames_.push_back({});
}

void FrameRecorder::noteUpload(double ms) {
  if (inFrame_ && !frames_.empty()) frames_.back().uploadMs += ms;
}

void FrameRecorder::noteRender(int level, double ms) {
  if (!inFrame_ || frames_.empty()) return;
  frames_.back().level = level;
  frames_.back().renderMs = ms;
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
  std::map<int, int> perLevel;
  int overBudget = 0;
  for (const Frame& f : frames_) {
    if (f.uploadMs > 0) uploads.push_back(f.uploadMs);
    if (f.level >= 0) renders.push_back(f.renderMs);
    if (f.ms > context.frameBudgetMs) ++overBudget;
    all.push_back(f.ms);
    (f.interacting ? moving : rest).push_back(f.ms);
    perLevel[f.level]++;
  }
  const auto maxOf = [](const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); };
  json levels = json::object();
  for (const auto& [l, n] : perLevel) levels[l < 0 ? "reused" : std::to_string(l)] = n;
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
          {"renders", renders.size()},
          {"render_ms_p50", percentile(renders, 50)},
          {"render_ms_max", maxOf(renders)},
          {"highlights", latencies_.size()},
          {"highlight_ms_p50", percentile(latencies_, 50)},
          {"highlight_ms_p99", percentile(latencies_, 99)},
          {"highlight_ms_max", maxOf(latencies_)},
          {"fields_cancelled", context.fieldsCancelled},
          {"window", context.window},
          {"gl", context.gl}};
}

}  // namespace at::app
