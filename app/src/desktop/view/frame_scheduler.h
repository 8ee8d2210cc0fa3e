// Adaptive quality for the volume view (no SDL, GL or ImGui here): which image to render this
// frame, and the measurements a `report` prints.
//
// While the view changes (its revision moves, or the user acts: `activity`), the volume is
// rendered whole into a smaller target with longer steps and no shading — the finest level whose
// predicted cost fits the interaction budget (on a fast GPU that is the full level itself). Once
// nothing has changed for kRestAfterMs, the full level (shading, jitter, the base step) is cast
// progressively (render/gl VolumeRenderer::refine): each frame casts the rays that fit in what
// the frame budget leaves besides the frame's other work (at most kRefineShareOfFrame), and the view shows the refined image as soon as it is at least as sharp
// as the one on screen, until it is complete. The full level's resolution is the view's times
// the render scale times a factor chosen when the rest begins, from the measured cost per ray of
// the full level, so that the image converges within kConvergeMs of casting (slow software GL:
// fewer, upsampled pixels; a GPU: the view's resolution). Asked for full quality (scripted
// screenshots), the factor is 1 and one frame casts the whole image. An unchanged view is not
// rendered again. The interaction cost model is one number: measured milliseconds per
// (pixel / step factor), an exponential moving average over the whole-image renders.
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
// No change for this long = the user rests (a drag moves every frame; a pause of 150 ms starts the
// full level, which on the 2-core CPU needs the rest of the 2 s the issue allows).
inline constexpr double kRestAfterMs = 150;
// Casting time the full level may take at rest: with the rest delay and the frames' UI share, the
// view is at full quality about 2 s after the last change.
inline constexpr double kConvergeMs = 1400;
inline constexpr double kRefineShareOfFrame = 0.6;  // of the frame budget, at most, per frame at rest
inline constexpr double kMinFullScale = 0.25;       // the full level never drops below this share of the view

// The image to render this frame.
struct RenderPlan {
  int level = kFullLevel;
  int width = 0, height = 0;  // pixels of the volume image
  double stepFactor = 1;      // times the volume's base step
  bool shading = true;        // only at full quality
  bool jitter = true;
  bool progressive = false;   // cast with VolumeRenderer::refine, `budgetMs` this frame
  double budgetMs = 0;
};

// Where a progressive image stands after a frame's refine call (render/gl's RefineProgress).
struct RefineReport {
  bool complete = false;
  bool displayable = false;  // its coarsest lattice is complete
  int stride = 8;            // of its finest complete lattice (1 when complete)
  double fraction = 0;       // of its pixels cast
  double imageMs = 0;        // casting time spent on it so far
  double callMs = 0;         // this call's
};

class FrameScheduler {
 public:
  // `frameBudgetMs`: a frame at rest casts rays for kRefineShareOfFrame of it. `renderScale`:
  // the largest resolution of the full level relative to the view.
  FrameScheduler(double frameBudgetMs, double renderScale);

  // The view's size in framebuffer pixels (the window minus the left panel).
  void setViewPixels(int width, int height);
  // A level's image at the render scale (the full level: at the largest resolution).
  RenderPlan planFor(int level) const;

  // This frame's decision for the view at `revision`; nullopt keeps the image on screen.
  // `activity` changes whenever the user acts (hover, drag, …) even if the image does not;
  // `fullQuality`: the full level at the render scale, cast in one frame (scripted screenshots).
  std::optional<RenderPlan> plan(std::uint64_t revision, std::uint64_t activity, Clock::time_point now,
                                 bool fullQuality = false);
  // A whole-image plan was rendered in `ms`, or a plan failed: the next frame starts the view
  // over (a GL error costs a frame, the renderer rebuilds its state), up to kRetriesAfterFailure
  // times in a row; after that the view is not rendered again until it changes.
  static constexpr int kRetriesAfterFailure = 2;
  void rendered(const RenderPlan& plan, double ms);
  void failed();
  // A progressive plan's refine call ended as `report` says, at `now`. Returns whether the view
  // is to show the refined image now (it is complete, or at least as sharp as the image shown).
  bool refined(const RenderPlan& plan, const RefineReport& report, Clock::time_point now);
  // A frame took `frameMs`, `renderMs` of it rendering: the rest (UI, field uploads, swap) is
  // what a refine call must leave room for.
  void frameTook(double frameMs, double renderMs);
  double refineBudgetMs() const;

  // The image on screen shows `revision` at full quality.
  bool finished(std::uint64_t revision) const;
  bool showing(std::uint64_t revision) const { return renderedRevision_ && *renderedRevision_ == revision; }
  int renderedLevel() const { return renderedLevel_; }
  bool interacting() const { return interacting_; }
  bool refining() const { return refining_ && renderedLevel_ < kFullLevel; }
  double refinedFraction() const { return refinedFraction_; }
  double msPerUnit() const { return msPerUnit_; }
  // The full level's resolution factor at rest (over the render scale) and the full level's
  // measured casting cost per pixel (0 before any).
  double fullScale() const { return fullScale_; }
  double msPerFullPixel() const { return msPerFullPixel_; }
  // Milliseconds from the last change of the view (or the user's last action) to the full level
  // on screen, for the image shown now; nullopt while it is not there.
  std::optional<double> settledAfterMs() const { return settledAfterMs_; }

 private:
  double costMs(int level) const;     // predicted; 0 before the first render
  double scaleForConvergence() const; // the full level's factor that converges in kConvergeMs
  RenderPlan fullPlan(double scale) const;
  double frameBudgetMs_, renderScale_;
  int viewW_ = 1, viewH_ = 1;
  std::optional<std::uint64_t> renderedRevision_;
  std::uint64_t lastActivity_ = 0;
  int renderedLevel_ = -1;
  int shownWidth_ = 0;  // pixels across of the image on screen
  double msPerUnit_ = 0;
  Clock::time_point lastChange_ = Clock::now();
  bool interacting_ = false;
  bool refining_ = false;      // this rest's progressive image has begun
  int restarts_ = 0;           // this rest's images started over smaller
  int failures_ = 0;           // plans of failedRevision_ failed since the last one that rendered
  std::optional<std::uint64_t> failedRevision_;
  double overshoot_ = 1;       // refine calls' time over their budget (moving average, ≥ 1)
  double fullScale_ = 1, msPerFullPixel_ = 0, refinedFraction_ = 0;
  double otherMs_ = 0;  // a frame's time besides rendering (moving average)
  std::optional<double> settledAfterMs_;
};

// Where one frame's time went (DesktopApp::frame's phases, the renderer's preparation inside the
// view's), for the report's breakdown of frames over the budget.
struct FramePhases {
  double inputMs = 0;  // events and the UI script's step
  double modelMs = 0;  // the model's per-frame work: polls, field requests and uploads
  double viewMs = 0;   // the volume view: a render or refine call, its preparation included
  double uiMs = 0;     // the panels, drawing the window and the swap
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
  void noteRefine(double ms);  // a refine call of the progressive full level
  // The renderer's preparation in this frame (render/gl PrepareCosts).
  void notePrepare(double prepareMs, double maskMs, double tableMs, double occupancyMs, int firstUses);
  void notePhases(const FramePhases& phases);  // before endFrame
  // The full level reached the screen `ms` after the view last changed, at `scale` of the view.
  void noteSettled(double ms, double scale);
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
    bool refine = false;     // the render was a refine call (level: the full level's)
    FramePhases phases;
    double prepareMs = 0, maskMs = 0, tableMs = 0, occupancyMs = 0;  // inside renderMs
    int firstUses = 0;       // ray-caster variants dispatched for the first time
    double atMs = 0;         // the frame's start, from the recording's
  };
  Clock::time_point recordingStart_;
  bool recording_ = false;
  bool inFrame_ = false;
  std::vector<Frame> frames_;
  std::vector<double> latencies_;
  std::vector<double> settles_, settleScales_;
  std::optional<std::pair<std::uint16_t, Clock::time_point>> pendingHighlight_;
};

// The p-th percentile (0..100) with linear interpolation; 0 for no values.
double percentile(std::vector<double> values, double p);

}  // namespace at::app
