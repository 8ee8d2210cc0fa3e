// The explore state without a window: what the image shows and when its revision moves.
#include <doctest/doctest.h>

#include "view/explore_state.h"
#include "test_support.h"

using namespace at;
using app::ExploreState;

namespace {

struct Fixture {
  const Dataset& dataset = test::phantomOfSize(48);
  render::PresetLibrary library{test::sourceDir() / "data" / "presets"};
  std::vector<std::string> messages;
  ExploreState state{library, [this](const std::string& m) { messages.push_back(m); }};
  Fixture() { REQUIRE(state.setDataset(dataset, "cochlea", "")); }
  std::uint16_t label(const std::string& id) const { return dataset.findStructure(id)->label; }
};

}  // namespace

TEST_CASE("ExploreState_StartsOnTheAskedStructure_WithItsWdtPresetShownBareUntilAFieldIsOnScreen") {
  Fixture f;
  CHECK(f.state.selected() == f.label("cochlea"));
  CHECK(f.state.hovered() == 0);
  CHECK_FALSE(f.state.bare());
  const auto shown = f.state.shown();
  CHECK(shown.label == f.label("cochlea"));
  CHECK((shown.preset.mode == render::RenderMode::Bare));  // no field yet
  f.state.setFieldShown(f.label("cochlea"), "key");
  CHECK((f.state.shown().preset.mode == render::RenderMode::Wdt));
  CHECK(f.state.shown().preset.t == doctest::Approx(f.state.t()));
  CHECK(f.messages.empty());
}

TEST_CASE("ExploreState_HoverInAFieldMode_KeepsTheImageUntilTheHoveredFieldArrives") {
  Fixture f;
  f.state.setFieldShown(f.label("cochlea"), "k1");
  const auto revision = f.state.revision(), activity = f.state.activity();
  REQUIRE(f.state.setHovered(f.label("stapes")));
  CHECK(f.state.revision() == revision);       // the cochlea's field is still what is shown
  CHECK(f.state.activity() > activity);        // but the user moved: the scheduler waits for rest
  CHECK(f.state.shown().label == f.label("cochlea"));
  CHECK(f.state.shownLabel() == f.label("stapes"));
  f.state.setFieldShown(f.label("stapes"), "k2");
  CHECK(f.state.revision() > revision);
  CHECK(f.state.shown().label == f.label("stapes"));
  CHECK_FALSE(f.state.setHovered(f.label("stapes")));  // the same structure: nothing changes
}

TEST_CASE("ExploreState_HoverInBareMode_ChangesTheImageAtOnce") {
  Fixture f;
  REQUIRE(f.state.setBare(true));
  const auto revision = f.state.revision();
  f.state.setHovered(f.label("malleus"));
  CHECK(f.state.revision() > revision);
  CHECK(f.state.shown().label == f.label("malleus"));
  CHECK((f.state.shown().preset.mode == render::RenderMode::Bare));
}

TEST_CASE("ExploreState_RevisionMovesOnlyWhenSomethingChanges") {
  Fixture f;
  auto r = f.state.revision();
  CHECK_FALSE(f.state.setT(f.state.t()));
  CHECK(f.state.revision() == r);
  CHECK(f.state.setT(0.9f));
  CHECK(f.state.revision() > r);
  r = f.state.revision();
  CHECK_FALSE(f.state.setT(2.0f) == false);  // clamped to 1: a change
  CHECK(f.state.t() == 1.0f);
  CHECK(f.state.revision() > r);
  r = f.state.revision();
  app::ClipSettings clip = f.state.clip();
  CHECK_FALSE(f.state.setClip(clip));
  clip.on = true;
  clip.axis = 7;  // clamped
  CHECK(f.state.setClip(clip));
  CHECK(f.state.clip().axis == 2);
  CHECK(f.state.clipPlane().has_value());
  CHECK(f.state.revision() > r);
  r = f.state.revision();
  f.state.orbit(10, 0);
  CHECK(f.state.revision() > r);
  r = f.state.revision();
  // A step preset equal to the one in use changes nothing (the study view sets it every frame).
  const render::Preset p = f.state.presetOf(f.label("cochlea"), false);
  f.state.usePreset(f.label("cochlea"), p, f.state.t());
  r = f.state.revision();
  CHECK_FALSE(f.state.usePreset(f.label("cochlea"), p, f.state.t()));
  CHECK(f.state.revision() == r);
}

TEST_CASE("ExploreState_ExpertOverride_DrivesModeAndTAndFieldParameters") {
  Fixture f;
  render::Preset edited = f.state.presetOf(f.label("cochlea"), false);
  edited.t = 0.25f;
  edited.weightRule = "trapezoid";
  f.state.setPresetOverride(edited, 1);
  CHECK(f.state.t() == 0.25f);
  CHECK(f.state.presetOverridden());
  auto params = f.state.fieldParams(f.label("stapes"));
  REQUIRE(params);
  CHECK((params->rule == StepRule::Trapezoid));
  const auto r = f.state.revision();
  f.state.setPresetOverride(edited, 1);  // the same edit: nothing new
  CHECK(f.state.revision() == r);
  f.state.setPresetOverride(std::nullopt, 2);
  CHECK_FALSE(f.state.presetOverridden());
  CHECK(f.state.revision() > r);
}

TEST_CASE("ExploreState_UnknownView_IsAnErrorAndKeepsTheCamera") {
  Fixture f;
  REQUIRE(f.state.setView("superior", 800, 600));
  const Vec3 eye = f.state.camera().eye();
  CHECK(f.state.viewName() == "superior");
  CHECK_FALSE(f.state.setView("diagonal", 800, 600));
  CHECK(f.state.camera().eye()[0] == eye[0]);
  CHECK(f.state.viewName() == "superior");
}

TEST_CASE("ExploreState_DatasetWithoutStructures_IsShownWholeWithItsDataTfFramedAroundTheGrid") {
  Fixture f;
  Dataset unlabelled;
  unlabelled.id = "unlabelled";
  unlabelled.volume = f.dataset.volume;  // the phantom's CT without its labels
  unlabelled.intensity = f.dataset.intensity;
  REQUIRE(f.state.setDataset(unlabelled, "cochlea", ""));
  CHECK(f.state.wholeVolume());
  CHECK(f.state.dataset().id == "unlabelled");
  CHECK(f.state.selected() == 0);
  CHECK(f.state.bySystem().empty());
  CHECK_FALSE(f.state.select(f.label("cochlea")));  // no structure to select
  // WDT mode at t = 1 with the whole-volume data TF, without waiting for any field.
  const auto shown = f.state.shown();
  CHECK(shown.label == 0);
  CHECK((shown.preset.mode == render::RenderMode::Wdt));
  CHECK(shown.preset.t == doctest::Approx(1.0));
  CHECK(shown.preset.id == std::optional<std::string>("whole_volume"));
  CHECK_FALSE(f.state.setBare(true));  // bare mode shows a structure alone: there is none
  // Framed around the grid's centre.
  REQUIRE(f.state.setView("anterior", 800, 600));
  const Vec3 centre = f.dataset.volume.geometry.centreMm();
  for (std::size_t a = 0; a < 3; ++a) CHECK(f.state.camera().target[a] == doctest::Approx(centre[a]).epsilon(1e-6));
  REQUIRE(f.state.frameOf(0) != nullptr);
  CHECK(f.state.frameOf(0)->radiusMm > 0);
  // A labelled dataset again: structures, no whole-volume mode.
  REQUIRE(f.state.setDataset(f.dataset, "cochlea", ""));
  CHECK_FALSE(f.state.wholeVolume());
  CHECK(f.state.selected() == f.label("cochlea"));
  CHECK(f.state.frameOf(0) == nullptr);
}

TEST_CASE("ExploreState_CourseStartPresetOnADatasetWithoutItsStructure_IsNotGivenToTheFirstStructure") {
  Fixture f;
  // The course's start (cochlea with its shipped preset) on the phantom: that preset.
  REQUIRE(f.state.setDataset(f.dataset, "cochlea", "cochlea_wdt"));
  f.state.setFieldShown(f.label("cochlea"), "key");
  CHECK(f.state.shown().preset.id == std::optional<std::string>("cochlea_wdt"));
  // A uint8 µCT-like scan whose structures have other names: its first structure gets its own
  // (derived) preset, not the cochlea's HU window.
  Dataset other = f.dataset;
  other.id = "other";
  for (Structure& s : other.structures) s.id = "scan_" + s.id, s.displayName = "Scan " + s.displayName;
  REQUIRE(f.state.setDataset(other, "cochlea", "cochlea_wdt"));
  const std::uint16_t first = f.state.selected();
  REQUIRE(first != 0);
  f.state.setFieldShown(first, "key");
  CHECK(f.state.shown().preset.id != std::optional<std::string>("cochlea_wdt"));
}

// A structure chosen in a view framed on another may lie (partly) outside it: bringIntoView frames
// it from the side the camera looks from, for every structure of the dataset and from every named
// side, zoomed in as far as a user may have; a structure the view shows whole keeps the camera.
TEST_CASE("ExploreState_BringIntoView_FramesAStructureOutsideTheViewFromTheSameSide_AndLeavesOneShownWholeAlone") {
  Fixture f;
  const int w = 800, h = 480;
  int movedCount = 0, keptCount = 0;
  for (const char* view : {"anterior", "lateral_left", "superior"}) {
    for (const Structure& s : f.dataset.structures) {
      CAPTURE(view);
      CAPTURE(s.id);
      REQUIRE(f.state.select(f.label("cochlea")));
      REQUIRE(f.state.setView(view, w, h));
      const render::Camera viewed = f.state.camera();
      CHECK_FALSE(f.state.bringIntoView(f.label("cochlea"), w, h));  // framed by the view: shown whole
      CHECK(f.state.camera() == viewed);
      f.state.zoom(6);  // the user zoomed in on the cochlea
      const render::Camera zoomed = f.state.camera();
      const render::StructureFrame& frame = *f.state.frameOf(s.label);
      const double before = render::shareInView(frame, zoomed, w, h);
      const double framedDistance = render::frameCamera(frame, zoomed, double(w) / h, 2.5).distanceMm;
      REQUIRE(f.state.select(s.label));
      const auto revision = f.state.revision();
      const bool moved = f.state.bringIntoView(s.label, w, h);
      CHECK(moved == (before < ExploreState::kShownWhole || zoomed.distanceMm > ExploreState::kFarthestShown * framedDistance));
      CHECK(render::shareInView(frame, f.state.camera(), w, h) >= ExploreState::kShownWhole);
      // The same side and the same up: only the target and the distance change.
      for (std::size_t a = 0; a < 3; ++a) {
        CHECK(f.state.camera().forward()[a] == doctest::Approx(zoomed.forward()[a]));
        CHECK(f.state.camera().up()[a] == doctest::Approx(zoomed.up()[a]));
      }
      ++(moved ? movedCount : keptCount);
      if (moved) {
        CHECK(f.state.revision() > revision);
        CHECK(f.state.framedCamera() == f.state.camera());  // the field's unit is judged on this view
      } else {
        CHECK(f.state.camera() == zoomed);
      }
      // Shown whole now: a second call changes nothing.
      const render::Camera framed = f.state.camera();
      CHECK_FALSE(f.state.bringIntoView(s.label, w, h));
      CHECK(f.state.camera() == framed);
    }
  }
  MESSAGE(movedCount << " structures framed, " << keptCount << " shown whole already");
  CHECK(movedCount > 0);
  // Shown whole but small: the cochlea's view zoomed out, a structure inside it chosen.
  REQUIRE(f.state.select(f.label("cochlea")));
  REQUIRE(f.state.setView("anterior", w, h));
  f.state.zoom(1.0 / 8);
  const render::Camera far = f.state.camera();
  REQUIRE(render::shareInView(*f.state.frameOf(f.label("cochlea")), far, w, h) == 1.0);
  CHECK(f.state.bringIntoView(f.label("cochlea"), w, h));
  CHECK(f.state.camera().distanceMm == doctest::Approx(far.distanceMm / 8));
}

TEST_CASE("FrameCamera_FromANamedCameraSide_IsTheNamedViewsFraming") {
  Fixture f;
  for (const Structure& s : f.dataset.structures) {
    const render::StructureFrame& frame = *f.state.frameOf(s.label);
    for (render::NamedView v : {render::NamedView::Anterior, render::NamedView::LateralRight, render::NamedView::Inferior}) {
      const render::Camera named = render::frameCamera(frame, v, 1.5, 2.5);
      const render::Camera along = render::frameCamera(frame, render::Camera::named(v, {0, 0, 0}, 100), 1.5, 2.5);
      CAPTURE(s.id);
      CHECK(along == named);
      CHECK(render::shareInView(frame, named, 600, 400) == 1.0);
    }
  }
}
