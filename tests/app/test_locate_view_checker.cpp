// The locate view check as the desktop keeps it (question_visibility.h): one checker per dataset on
// screen, sharing the desktop's gradients and reading its own copy of the labels, answers as a
// fresh checker does, check after check; labels given to it later are the ones it checks on; a
// cancelled check stops with a Cancelled error.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>

#include "question_visibility.h"
#include "render/gradient_volume.h"
#include "render/preset.h"
#include "test_support.h"
#include "volume/dataset_source.h"

using namespace at;

namespace {

quiz::Question locate(const std::string& target) {
  quiz::Question q;
  q.id = "q_" + target;
  q.kind = quiz::QuestionKind::Locate;
  q.prompt = "Click the " + target + ".";
  q.target = target;
  return q;
}

lessons::QuestionScene sceneOn(const std::string& region, lessons::CameraView view) {
  lessons::QuestionScene s;
  s.structure = region;
  s.view = view;
  return s;
}

// The 64³ phantom and the vestibule's shipped WDT preset, on which every case here asks "Click the
// cochlea" from the front.
struct VestibuleScene {
  Dataset dataset;
  render::Preset preset;
};

VestibuleScene vestibuleScene() {
  auto dataset = openBuiltinDataset("phantom:64");
  REQUIRE(dataset);
  const render::PresetLibrary library(test::sourceDir() / "data" / "presets");
  auto preset = library.load("vestibule_wdt");
  REQUIRE(preset);
  return {std::move(*dataset), std::move(*preset)};
}

void checkSame(const Result<app::LocateCheck>& a, const Result<app::LocateCheck>& b) {
  REQUIRE_MESSAGE(a, (a ? "" : a.error().message));
  REQUIRE_MESSAGE(b, (b ? "" : b.error().message));
  CHECK(a->answerable == b->answerable);
  CHECK(a->problem == b->problem);
  CHECK(a->pickingPixels == b->pickingPixels);
  CHECK(a->shownPixels == b->shownPixels);
}

}  // namespace

TEST_CASE("LocateViewChecker_KeptWithSharedGradientsAndItsOwnLabels_AnswersAsAFreshCheckerCheckAfterCheck") {
  const VestibuleScene scene = vestibuleScene();
  const Dataset& dataset = scene.dataset;
  const render::Preset& preset = scene.preset;
  const render::GradientVolume gradients = render::computeGradientVolume(dataset.volume);
  app::LocateViewChecker kept(dataset, gradients);
  kept.useLabels(dataset.labels, dataset.structures);

  const auto anterior = sceneOn("vestibule", lessons::CameraView::Anterior);
  const auto fresh = app::LocateViewChecker(dataset).check(locate("cochlea"), anterior, preset);
  checkSame(kept.check(locate("cochlea"), anterior, preset), fresh);
  checkSame(kept.check(locate("cochlea"), anterior, preset), fresh);  // on the region's kept field
  // A preset edited under the same id (the expert panel) makes its own field.
  render::Preset edited = preset;
  edited.huWindow = {edited.huWindow[0], edited.huWindow[1] * 2};
  checkSame(kept.check(locate("cochlea"), anterior, edited), app::LocateViewChecker(dataset).check(locate("cochlea"), anterior, edited));

  // The cochlea erased from the checker's copy of the labels (the segment editor's edit): its
  // checks read the copy, not the dataset's own labels (which the fresh check above read).
  LabelMap erased = dataset.labels;
  const std::uint16_t cochlea = dataset.findStructure("cochlea")->label;
  std::replace(erased.voxels.begin(), erased.voxels.end(), cochlea, std::uint16_t(0));
  kept.useLabels(std::move(erased), dataset.structures);
  auto gone = kept.check(locate("cochlea"), anterior, preset);
  REQUIRE(gone);
  CHECK_FALSE(gone->answerable);
  CHECK(gone->problem == "the target or its region has no voxels");
  CHECK(fresh->pickingPixels > 0);
}

TEST_CASE("LocateViewChecker_CancelSet_ReturnsACancelledErrorThenChecksAsBefore") {
  const VestibuleScene scene = vestibuleScene();
  const Dataset& dataset = scene.dataset;
  const render::Preset& preset = scene.preset;
  app::LocateViewChecker checker(dataset);
  const auto anterior = sceneOn("vestibule", lessons::CameraView::Anterior);
  std::atomic<bool> cancel{true};
  auto cancelled = checker.check(locate("cochlea"), anterior, preset, &cancel);
  REQUIRE_FALSE(cancelled);
  CHECK((cancelled.error().kind == ErrorKind::Cancelled));
  cancel = false;
  auto checked = checker.check(locate("cochlea"), anterior, preset, &cancel);
  REQUIRE_MESSAGE(checked, (checked ? "" : checked.error().message));
  CHECK(checked->pickingPixels > 0);
}
