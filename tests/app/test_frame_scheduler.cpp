// The frame scheduler and recorder without a window: which quality level each frame renders, when
// the view rests, the frame budget at rest, and the report's numbers.
#include <doctest/doctest.h>

#include "frame_scheduler.h"

using namespace at::app;

namespace {
Clock::time_point atMs(double ms) { return Clock::time_point() + std::chrono::microseconds(std::int64_t(ms * 1000)); }
}  // namespace

TEST_CASE("FrameScheduler_FullLevel_IsTheViewAtTheRenderScale_WithShading") {
  FrameScheduler s(100, 0.5);
  s.setViewPixels(960, 720);
  const RenderPlan full = s.planFor(kFullLevel);
  CHECK(full.width == 480);
  CHECK(full.height == 360);
  CHECK(full.shading);
  CHECK(full.jitter);
  const RenderPlan coarse = s.planFor(0);
  CHECK(coarse.width == 24);
  CHECK(coarse.stepFactor == 4.0);
  CHECK_FALSE(coarse.shading);
}

TEST_CASE("FrameScheduler_WithoutACostModel_StartsCoarse_RefinesOneLevelPerRestedFrame_ThenStops") {
  FrameScheduler s(1e9, 1);
  s.setViewPixels(400, 300);
  auto p = s.plan(1, 1, atMs(0), false);
  REQUIRE(p);
  CHECK(p->level == 0);
  CHECK(s.interacting());
  s.rendered(*p, 0);
  CHECK_FALSE(s.plan(1, 1, atMs(100), false));  // not rested yet: the image stays
  int level = 0;
  for (int frame = 0; frame < 20 && !s.finished(1); ++frame) {
    auto q = s.plan(1, 1, atMs(300 + frame), false);
    if (!q) continue;
    CHECK(q->level == level + 1);
    level = q->level;
    s.rendered(*q, 0);
  }
  CHECK(level == kFullLevel);
  CHECK(s.finished(1));
  CHECK_FALSE(s.plan(1, 1, atMs(1000), false));
  // A new revision starts over; activity alone (a hover over the same structure) only delays.
  CHECK(s.plan(2, 1, atMs(1001), false));
}

TEST_CASE("FrameScheduler_WithACostModel_PicksTheFinestLevelFittingTheInteractionBudget") {
  FrameScheduler s(1e9, 1);
  s.setViewPixels(1000, 1000);
  RenderPlan full = s.planFor(kFullLevel);
  s.rendered(full, 1000.0);  // 1e-3 ms per pixel: full level 1000 ms, level 3 (350², /1.5) ≈ 82 ms, level 2 20 ms
  auto p = s.plan(5, 1, atMs(0), false);
  REQUIRE(p);
  CHECK(p->level == 2);
  s.rendered(*p, 20);
  // At rest: levels predicted under 150 ms are skipped over, so the next render is level 3 or finer.
  auto q = s.plan(5, 1, atMs(400), false);
  REQUIRE(q);
  CHECK(q->level >= 3);
}

TEST_CASE("FrameScheduler_FrameBudgetAtRest_CapsTheLevel_UnlessFullQualityIsAsked") {
  FrameScheduler s(100, 1);
  s.setViewPixels(1000, 1000);
  s.rendered(s.planFor(kFullLevel), 1000.0);  // full level costs 1000 ms: over the 100 ms budget
  auto p = s.plan(7, 1, atMs(0), false);
  REQUIRE(p);
  s.rendered(*p, 1e-3 * p->width * p->height / p->stepFactor);
  for (int frame = 0; frame < 10; ++frame)
    if (auto q = s.plan(7, 1, atMs(400 + frame), false)) s.rendered(*q, 1e-3 * q->width * q->height / q->stepFactor);
  CHECK(s.finished(7));
  CHECK(s.renderedLevel() < kFullLevel);
  auto full = s.plan(7, 2, atMs(1000), true);  // the box ticked (activity) and rested
  CHECK_FALSE(full);
  full = s.plan(7, 2, atMs(1300), true);
  REQUIRE(full);
  CHECK(full->level > s.renderedLevel());
}

TEST_CASE("FrameRecorder_Report_CountsFramesLevelsUploadsAndHighlightLatency") {
  FrameRecorder r;
  r.highlightWanted(3, atMs(0));
  r.beginFrame();  // not recording: nothing kept
  r.endFrame(10, true);
  r.start();
  r.highlightWanted(3, atMs(0));
  r.beginFrame();
  r.noteUpload(4);
  r.noteRender(2, 30);
  r.frameShown(true, 2, atMs(40));  // another structure on screen: still waiting
  r.endFrame(40, true);
  r.beginFrame();
  r.frameShown(true, 3, atMs(90));
  r.endFrame(12, false);
  FrameRecorder::Context context;
  context.frameBudgetMs = 30;
  context.window = "800x480";
  const auto report = r.report(context);
  CHECK(report["frames"] == 2);
  CHECK(report["frames_per_level"]["2"] == 1);
  CHECK(report["frames_per_level"]["reused"] == 1);
  CHECK(report["field_uploads"] == 1);
  CHECK(report["frames_over_budget"] == 1);
  CHECK(report["highlights"] == 1);
  CHECK(report["highlight_ms_max"].get<double>() == doctest::Approx(90));
  CHECK(report["moving_frames"] == 1);
  CHECK(report["window"] == "800x480");
  CHECK(percentile({1, 2, 3, 4}, 50) == doctest::Approx(2.5));
}
