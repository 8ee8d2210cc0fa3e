// The frame scheduler and recorder without a window: which quality level each frame renders, when
// the view rests, the full level refined progressively at rest at a size that converges in time,
// and the report's numbers.
#include <doctest/doctest.h>

#include "view/frame_scheduler.h"

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

TEST_CASE("FrameScheduler_WithoutACostModel_StartsCoarse_ThenRefinesTheFullLevelProgressivelyAtRest") {
  FrameScheduler s(100, 1);
  s.setViewPixels(400, 300);
  auto p = s.plan(1, 1, atMs(0));
  REQUIRE(p);
  CHECK(p->level == 0);
  CHECK_FALSE(p->progressive);
  CHECK(s.interacting());
  s.rendered(*p, 0);  // 20 × 16 pixels on screen
  CHECK_FALSE(s.plan(1, 1, atMs(100)));  // not rested yet: the image stays
  auto r = s.plan(1, 1, atMs(300));
  REQUIRE(r);
  CHECK(r->progressive);
  CHECK(r->level == kFullLevel);
  CHECK(r->shading);
  CHECK(r->width == 400);  // no refine cost known yet: the view's resolution
  CHECK(r->budgetMs == doctest::Approx(kRefineShareOfFrame * 100));
  CHECK_FALSE(s.interacting());
  CHECK(s.refining());

  // Not shown before its coarsest lattice exists, nor while coarser than the image on screen.
  RefineReport report;
  report.fraction = 0.001;
  report.imageMs = 0.12;  // 1e-3 ms per pixel: 120 ms for the whole image, well within kConvergeMs
  CHECK_FALSE(s.refined(*r, report, atMs(310)));
  auto again = s.plan(1, 1, atMs(320));
  REQUIRE(again);
  CHECK(again->width == 400);  // the measured cost converges in time: no restart at a smaller size
  report.displayable = true;
  report.stride = 8;  // 50 pixels across ≥ the 20 shown
  report.fraction = 0.02;
  CHECK(s.refined(*again, report, atMs(330)));
  CHECK_FALSE(s.finished(1));
  CHECK_FALSE(s.settledAfterMs());
  report.complete = true;
  report.stride = 1;
  report.fraction = 1;
  CHECK(s.refined(*again, report, atMs(450)));
  CHECK(s.finished(1));
  REQUIRE(s.settledAfterMs());
  CHECK(*s.settledAfterMs() == doctest::Approx(450));
  CHECK_FALSE(s.plan(1, 1, atMs(1000)));
  // A new revision starts over; activity alone (a hover over the same structure) only delays.
  CHECK(s.plan(2, 1, atMs(1001)));
}

TEST_CASE("FrameScheduler_AFailedPlan_IsPlannedAgainTwice_ThenLeftUntilTheViewChanges") {
  // A GL error costs one frame (the renderer rebuilds its state): the view is not left on an
  // older image. A failure that repeats is not retried every frame.
  FrameScheduler s(100, 1);
  s.setViewPixels(400, 300);
  auto p = s.plan(1, 1, atMs(0));
  REQUIRE(p);
  s.failed();
  auto retry = s.plan(1, 1, atMs(10));
  REQUIRE(retry);
  CHECK_FALSE(retry->progressive);
  s.rendered(*retry, 5);
  auto rest = s.plan(1, 1, atMs(400));
  REQUIRE(rest);
  REQUIRE(rest->progressive);
  s.failed();  // a refine that failed: the rest starts over, as after a change
  CHECK_FALSE(s.finished(1));
  auto again = s.plan(1, 1, atMs(410));
  REQUIRE(again);
  CHECK_FALSE(again->progressive);
  s.failed();
  REQUIRE(s.plan(1, 1, atMs(420)));  // the second retry in a row
  s.failed();
  CHECK_FALSE(s.plan(1, 1, atMs(430)));  // the third failure in a row: left alone …
  CHECK_FALSE(s.plan(1, 1, atMs(900)));
  auto changed = s.plan(2, 1, atMs(910));  // … until the view changes, which has its own retries
  REQUIRE(changed);
  s.failed();
  CHECK(s.plan(2, 1, atMs(920)));
}

TEST_CASE("FrameScheduler_SlowFullLevel_RestartsSmallerOnce_SoThatTheImageConvergesInTime") {
  FrameScheduler s(100, 1);
  s.setViewPixels(1000, 1000);
  auto p = s.plan(1, 1, atMs(0));
  REQUIRE(p);
  s.rendered(*p, 1);
  auto r = s.plan(1, 1, atMs(300));
  REQUIRE(r);
  REQUIRE(r->width == 1000);
  RefineReport report;
  report.fraction = 0.006;
  report.imageMs = 60;  // 0.01 ms per pixel: 10 s for the whole image
  CHECK_FALSE(s.refined(*r, report, atMs(360)));
  auto smaller = s.plan(1, 1, atMs(370));
  REQUIRE(smaller);
  // √(1400 / 10000) of the view per axis: 374 pixels, 1.4 s.
  CHECK(smaller->width == 374);
  CHECK(s.fullScale() == doctest::Approx(0.374).epsilon(0.01));
  // The next rest starts at the measured size at once; asked for full quality, at the view's.
  report.complete = true;
  report.fraction = 1;
  report.imageMs = 1400;  // as predicted
  CHECK(s.refined(*smaller, report, atMs(2000)));
  REQUIRE(s.plan(2, 2, atMs(2001)));
  auto next = s.plan(2, 2, atMs(2300));
  REQUIRE(next);
  CHECK(next->width < 1000);
  REQUIRE(s.plan(3, 3, atMs(3000)));
  auto full = s.plan(3, 3, atMs(3300), true);
  REQUIRE(full);
  CHECK(full->width == 1000);
  CHECK(full->budgetMs >= 1e6);
}

TEST_CASE("FrameScheduler_WithACostModel_PicksTheFinestLevelFittingTheInteractionBudget") {
  FrameScheduler s(100, 1);
  s.setViewPixels(1000, 1000);
  RenderPlan full = s.planFor(kFullLevel);
  s.rendered(full, 1000.0);  // 1e-3 ms per pixel: full level 1000 ms, level 3 (350², /1.5) ≈ 82 ms, level 2 20 ms
  auto p = s.plan(5, 1, atMs(0));
  REQUIRE(p);
  CHECK(p->level == 2);
  s.rendered(*p, 20);
  auto q = s.plan(5, 1, atMs(400));  // at rest: the full level, progressively
  REQUIRE(q);
  CHECK(q->progressive);
  // A GPU: the full level fits the interaction budget and is rendered whole at once.
  FrameScheduler fast(100, 1);
  fast.setViewPixels(1000, 1000);
  fast.rendered(fast.planFor(kFullLevel), 5.0);
  auto f = fast.plan(1, 1, atMs(0));
  REQUIRE(f);
  CHECK(f->level == kFullLevel);
  CHECK_FALSE(f->progressive);
  fast.rendered(*f, 5.0);
  CHECK(fast.finished(1));
  CHECK_FALSE(fast.plan(1, 1, atMs(400)));
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
  r.noteSettled(1500, 0.5);
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
  CHECK(report["settles"] == 1);
  CHECK(report["settle_ms_max"].get<double>() == doctest::Approx(1500));
  CHECK(report["full_scale_min"].get<double>() == doctest::Approx(0.5));
  CHECK(report["window"] == "800x480");
  CHECK(percentile({1, 2, 3, 4}, 50) == doctest::Approx(2.5));
}
