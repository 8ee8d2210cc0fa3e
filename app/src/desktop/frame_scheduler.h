// Adaptive quality for the volume view (no SDL, GL or ImGui here): which image to render this
// frame, and the measurements a `report` prints.
//
// While the view changes (its revision moves, or the user acts: `activity`), the volume is
// rendered into a smaller target with longer steps — the finest level whose predicted cost fits
// the interaction budget. Once nothing has changed for kRestAfterMs, each frame renders one level
// finer (skipping levels predicted cheaper than kRefineBudgetMs), up to full resolution or, unless
// full quality is asked for, to the finest level predicted to fit the frame budget. An unchanged
// view is not rendered again. The cost model is one number: measured milliseconds per
// (pixel / step factor), an exponential moving average over the renders.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace at::app {

using Clock = std::chrono::steady_clock;

double msBetween(Clock::time_point a, Clock::time_point b);

// A render quality level: fraction of the view's pixels per axis and step length factor.
struct QualityLevel {
  double scale;
  double stepFactor;
};
inline constexpr QualityLevel kQualityLevels[] = {{0.05, 4.0}, {0.1, 3.0}, {0.2, 2.0}, {0.35, 1.5}, {0.6, 1.0}, {1.0, 1.0}};
inline constexpr int kFullLevel = 5;
inline constexpr double kInteractionBudgetMs = 55;  // predicted render cost allowed while the user moves
inline constexpr double kRefineBudgetMs = 150;      // at rest, levels predicted this cheap are skipped over
inline constexpr double kRestAfterMs = 250;         // no change for this long = the user rests

// The image to render this frame.
struct RenderPlan {
  int level = kFullLevel;
  int width = 0, height = 0;  // pixels of the volume image
  double stepFactor = 1;      // times the volume's base step
  bool shading = true;        // gradients cost six fetches per sample: only at full quality
  bool jitter = true;
};

class FrameScheduler {
 public:
  // `frameBudgetMs`: at rest, finer levels predicted to cost more are not rendered (unless full
  // quality is asked for). `renderScale`: resolution of the full level relative to the view.
  FrameScheduler(double frameBudgetMs, double renderScale);

  // The view's size in framebuffer pixels (the window minus the left panel).
  void setViewPixels(int width, int height);
  RenderPlan planFor(int level) const;

  // This frame's decision for the view at `revision`; nullopt keeps the image on screen.
  // `activity` changes whenever the user acts (hover, drag, …) even if the image does not;
  // `fullAtRest` lifts the frame budget at rest (the checkbox; scripted screenshots).
  std::optional<RenderPlan> plan(std::uint64_t revision, std::uint64_t activity, Clock::time_point now, bool fullAtRest);
  // The plan was rendered in `ms`, or failed (then the view is not rendered again until it changes).
  void rendered(const RenderPlan& plan, double ms);
  void failed();

  // The image on screen shows `revision` at its final quality (full, or the budget's cap).
  bool finished(std::uint64_t revision) const;
  bool showing(std::uint64_t revision) const { return renderedRevision_ && *renderedRevision_ == revision; }
  int renderedLevel() const { return renderedLevel_; }
  bool interacting() const { return interacting_; }
  double msPerUnit() const { return msPerUnit_; }

 private:
  double costMs(int level) const;  // predicted; 0 before the first render
  double frameBudgetMs_, renderScale_;
  int viewW_ = 1, viewH_ = 1;
  std::optional<std::uint64_t> renderedRevision_;
  std::uint64_t lastActivity_ = 0;
  int renderedLevel_ = -1;
  double msPerUnit_ = 0;
  Clock::time_point lastChange_ = Clock::now();
  bool interacting_ = false;
  bool restCapped_ = false;  // the image at rest stopped below full quality (frame budget)
};

// Frame times, render and upload costs and hover-to-highlight latencies while recording, and the
// `report` the hover benchmark prints (bench/RESULTS.md).
class FrameRecorder {
 public:
  void start();             // clears what was recorded
  void stop() { recording_ = false; }
  bool recording() const { return recording_; }

  void beginFrame();
  void noteUpload(double ms);
  void noteRender(int level, double ms);
  void endFrame(double ms, bool interacting);

  // Highlight latency: from a hover onto a structure to the first frame showing its context.
  void highlightWanted(std::uint16_t label, Clock::time_point since) { pendingHighlight_ = {label, since}; }
  void highlightNotWanted() { pendingHighlight_.reset(); }
  // At the end of a frame: `label` is what the image on screen shows now (`current`: the image is
  // of the view as it is).
  void frameShown(bool current, std::uint16_t label, Clock::time_point at);

  struct Context {
    double frameBudgetMs = 0;
    int fieldsCancelled = 0;
    std::string window, gl;
  };
  nlohmann::json report(const Context& context) const;
  double lastFrameMs() const { return frames_.empty() ? 0 : frames_.back().ms; }

 private:
  struct Frame {
    double ms = 0;
    int level = -1;          // quality level rendered in the frame, -1 when the image was reused
    bool interacting = false;
    double uploadMs = 0;     // distance field uploaded to the GL in the frame
    double renderMs = 0;     // the volume render of the frame (0 when reused)
  };
  bool recording_ = false;
  bool inFrame_ = false;
  std::vector<Frame> frames_;
  std::vector<double> latencies_;
  std::optional<std::pair<std::uint16_t, Clock::time_point>> pendingHighlight_;
};

// The p-th percentile (0..100) with linear interpolation; 0 for no values.
double percentile(std::vector<double> values, double p);

}  // namespace at::app
