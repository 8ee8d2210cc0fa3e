// The shown field's distance unit measured off the UI thread (view/field_unit.h): the unit taken
// is the one render::fieldScale measures, a superseded measure is never taken, and neither
// FieldUnits::unitFor nor the desktop's renderSettings waits for a running measure.
#include <doctest/doctest.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "desktop_model.h"
#include "headless_desktop.h"
#include "render/picture_scale.h"
#include "render/gradient_volume.h"
#include "render/preset.h"
#include "view/field_unit.h"
#include "volume/mask.h"
#include "wdt/wdt.h"
#include "test_support.h"

using namespace at;
using app::FieldUnitRequest;
using app::FieldUnits;

namespace {

// A guard against a hang, not a timing assert: every wait below ends long before this when the
// code is right.
constexpr auto kHangGuard = std::chrono::seconds(120);

// A stand-in measure that blocks each call until the test opens its id (label × 1000 + the view's
// width) and then returns a unit of 100 + that id, so that whose result was taken is visible.
struct Gates {
  std::mutex m;
  std::condition_variable cv;
  std::set<int> open;
  bool allOpen = false;
  std::vector<int> started;  // ids, in the order measured
  bool hung = false;         // a measure waited kHangGuard for its gate

  static int idOf(const FieldUnitRequest& r) { return r.key.label * 1000 + r.key.view.width; }
  static double unitOf(int id) { return 100.0 + id; }
  app::FieldUnitMeasure measure() {
    return [this](const FieldUnitRequest& r) {
      const int id = idOf(r);
      std::unique_lock lock(m);
      started.push_back(id);
      cv.notify_all();
      if (!cv.wait_for(lock, kHangGuard, [&] { return allOpen || open.count(id) > 0; })) hung = true;
      render::FieldScale s;
      s.distanceUnit = unitOf(id);
      s.derived = true;
      return s;
    };
  }
  void release(int id) {
    std::lock_guard lock(m);
    open.insert(id);
    cv.notify_all();
  }
  void releaseAll() {
    std::lock_guard lock(m);
    allOpen = true;
    cv.notify_all();
  }
  bool waitStarted(std::size_t count) {
    std::unique_lock lock(m);
    return cv.wait_for(lock, kHangGuard, [&] { return started.size() >= count; });
  }
  std::vector<int> startedIds() {
    std::lock_guard lock(m);
    return started;
  }
};

// Polls until a measure is taken (true) or the hang guard passes.
bool pollUntilTaken(FieldUnits& units) {
  const auto end = std::chrono::steady_clock::now() + kHangGuard;
  while (std::chrono::steady_clock::now() < end) {
    if (units.poll()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return false;
}

// A request on a field of its own (its address is the key's identity) for `label`.
FieldUnitRequest requestForInjectedMeasure(const Dataset& ds, std::uint16_t label, int viewWidth) {
  FieldUnitRequest r;
  auto field = std::make_shared<DistanceField>();
  r.field = field;
  r.key.field = field.get();
  r.key.label = label;
  r.key.seen = true;
  r.key.view.width = viewWidth;
  r.volume = &ds.volume;
  auto frame = render::structureFrame(ds.labels, label);
  REQUIRE(frame);
  r.frame = *frame;
  return r;
}

}  // namespace

TEST_CASE("FieldUnits_TheUnitTakenAfterTheAsyncMeasure_EqualsTheRenderCommandsUnit") {
  const Dataset& ds = test::phantomOfSize(48);
  const render::PresetLibrary library(test::sourceDir() / "data" / "presets");
  // Every structure, in a mode of each kind of unit (around, seen, the bone next to it, fuzzy's
  // judged on the picture): the unit render::applyFieldScale sets for the render command on the
  // same view.
  const render::GradientVolume gradients = render::computeGradientVolume(ds.volume);
  for (const char* presetId : {"cochlea_wdt", "cochlea_fuzzy", "cochlea_lighting"}) {
    CAPTURE(presetId);
    auto preset = library.load(presetId);
    REQUIRE_MESSAGE(preset, (preset ? "" : preset.error().message));
    auto params = render::wdtParamsFor(*preset);
    REQUIRE(params);
    for (const Structure& s : ds.structures) {
      CAPTURE(s.id);
      auto frame = render::structureFrame(ds.labels, s.label);
      if (!frame) continue;  // not in the volume at this size
      auto wdt = computeWdt(ds.volume, structureMask(ds.labels, s.label), *params);
      REQUIRE(wdt);
      auto field = std::make_shared<DistanceField>(std::move(wdt->field));
      render::RenderSettings settings;
      settings.preset = *preset;
      settings.camera = render::frameCamera(*frame, render::NamedView::LateralRight, 1.0);
      settings.width = settings.height = 96;
      const render::PictureInputs picture{&ds.labels, s.label, &gradients};
      const render::FieldScale sync =
          render::applyFieldScale(settings, field->distances, ds.volume, nullptr, *frame, render::ViewRequest{}, &picture);
      FieldUnitRequest r;
      r.field = field;
      r.volume = &ds.volume;
      r.frame = *frame;
      r.key.field = field.get();
      r.key.label = s.label;
      r.key.bone = render::boneLevels(*preset);
      r.key.mode = preset->mode;
      r.key.seen = render::unitFromSeenBone(preset->mode);
      r.key.view = render::fieldViewOf(settings);
      if (render::judgedOnPicture(preset->mode)) {  // as the desktop asks for it
        r.key.picturePreset = *preset;
        r.key.picturePreset.t = 0;
        r.labels = &ds.labels;
        r.gradients = &gradients;
      }
      FieldUnits units;  // measureFieldUnit on a worker
      CHECK_FALSE(units.unitFor(r).has_value());  // nothing taken for this structure yet: the caller's unit
      CHECK(units.measuring());
      REQUIRE(pollUntilTaken(units));
      CHECK_FALSE(units.measuring());
      const auto taken = units.unitFor(r);
      REQUIRE(taken);
      CHECK(taken->distanceUnit == sync.distanceUnit);
      CHECK(taken->distanceUnit == settings.distanceUnit);
      CHECK(taken->distanceOffset == sync.distanceOffset);
      CHECK(taken->derived == sync.derived);
      CHECK(taken->fromSeen == sync.fromSeen);
      CHECK(taken->fromNeighbours == sync.fromNeighbours);
      CHECK(taken->contextVoxels == sync.contextVoxels);
      CHECK(taken->pictureJudged == sync.pictureJudged);
      CHECK(taken->pictureJudged == render::judgedOnPicture(preset->mode));
      CHECK(taken->lightingReach == sync.lightingReach);
      CHECK(taken->fromPicture == sync.fromPicture);
      CHECK(taken->pictureNear == sync.pictureNear);
      CHECK_FALSE(units.measuring());  // the same key again: not measured again
      FieldUnits synchronous({}, true);  // the scripted desktop's way: the same unit at once
      const auto now = synchronous.unitFor(r);
      REQUIRE(now);
      CHECK(now->distanceUnit == sync.distanceUnit);
    }
  }
}

TEST_CASE("FieldUnits_ASupersededMeasure_IsNeverTaken_AndOnlyTheNewestWaitingKeyIsMeasured") {
  const Dataset& ds = test::phantomOfSize(48);
  const std::uint16_t a = ds.findStructure("cochlea")->label, b = ds.findStructure("stapes")->label;
  Gates gates;
  FieldUnits units(gates.measure());
  const FieldUnitRequest first = requestForInjectedMeasure(ds, a, 64);
  const FieldUnitRequest sameLabelOtherView = requestForInjectedMeasure(ds, a, 80);
  const FieldUnitRequest otherLabel = requestForInjectedMeasure(ds, b, 64);
  const FieldUnitRequest newest = requestForInjectedMeasure(ds, b, 96);

  // The first key is measured and taken: it is the stand-in for its label from now on.
  CHECK_FALSE(units.unitFor(first));
  gates.release(Gates::idOf(first));
  REQUIRE(pollUntilTaken(units));
  REQUIRE(units.unitFor(first));
  CHECK(units.unitFor(first)->distanceUnit == Gates::unitOf(Gates::idOf(first)));

  // Another view of the same structure: the last unit of the label meanwhile (returned at once,
  // its measure still blocked).
  auto meanwhile = units.unitFor(sameLabelOtherView);
  REQUIRE(meanwhile);
  CHECK(meanwhile->distanceUnit == Gates::unitOf(Gates::idOf(first)));
  REQUIRE(gates.waitStarted(2));
  // Two newer keys while it runs: the second replaces the first in the queue.
  CHECK_FALSE(units.unitFor(otherLabel));
  CHECK_FALSE(units.unitFor(newest));
  gates.release(Gates::idOf(sameLabelOtherView));
  gates.release(Gates::idOf(otherLabel));
  // The superseded result arrives and is dropped: poll says nothing was taken, and neither the
  // newest key nor the label it was measured for has it.
  const auto end = std::chrono::steady_clock::now() + kHangGuard;
  while (gates.startedIds().size() < 3 && std::chrono::steady_clock::now() < end) {
    CHECK_FALSE(units.poll());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  CHECK_FALSE(units.unitFor(newest));
  auto label = units.unitFor(first);  // the first key is still taken; the superseded view is not
  REQUIRE(label);
  CHECK(label->distanceUnit == Gates::unitOf(Gates::idOf(first)));
  units.unitFor(newest);  // wanted again
  gates.release(Gates::idOf(newest));
  REQUIRE(pollUntilTaken(units));
  auto taken = units.unitFor(newest);
  REQUIRE(taken);
  CHECK(taken->distanceUnit == Gates::unitOf(Gates::idOf(newest)));
  // Measured: the first, the superseded view and the newest key; the key replaced in the queue never.
  CHECK(gates.startedIds() ==
        std::vector<int>{Gates::idOf(first), Gates::idOf(sameLabelOtherView), Gates::idOf(newest)});
  CHECK_FALSE(gates.hung);
}

TEST_CASE("FieldUnits_BackToAStructureWhoseFieldStillLives_TakesItsUnitWithoutMeasuringAgain") {
  const Dataset& ds = test::phantomOfSize(48);
  Gates gates;
  gates.releaseAll();
  FieldUnits units(gates.measure());
  std::vector<FieldUnitRequest> requests;
  for (const Structure& s : ds.structures)
    if (render::structureFrame(ds.labels, s.label) && requests.size() < FieldUnits::kKeptUnits)
      requests.push_back(requestForInjectedMeasure(ds, s.label, 64));
  REQUIRE(requests.size() >= 3);
  for (const FieldUnitRequest& r : requests) {
    units.unitFor(r);
    REQUIRE(pollUntilTaken(units));
  }
  // Hovering back over each: its own unit at once, nothing measured again.
  for (const FieldUnitRequest& r : requests) {
    const auto unit = units.unitFor(r);
    REQUIRE(unit);
    CHECK(unit->distanceUnit == Gates::unitOf(Gates::idOf(r)));
  }
  CHECK_FALSE(units.measuring());
  CHECK(gates.startedIds().size() == requests.size());
}

TEST_CASE("DesktopModel_RenderSettings_DoesNotWaitForARunningUnitMeasure_AndRendersAgainWhenItIsTaken") {
  test::TempDir dir("field-units-desktop");
  auto session = app::LearningSession::open((dir / "t.db").string());
  REQUIRE_MESSAGE(session, test::errorText(session));
  const render::PresetLibrary library(test::sourceDir() / "data" / "presets");
  Gates gates;
  app::DesktopOptions options;
  options.dataset = "phantom:64";
  options.renderScale = 0.4;
  options.measureFieldUnit = gates.measure();  // not scripted: measured on a worker
  app::DesktopModel model(**session, library, options, [](nlohmann::json) {}, [](const std::string&) {});
  test::HeadlessOptions layout;
  model.setLayout(test::headlessLayout(layout));
  auto opened = model.open();
  REQUIRE_MESSAGE(opened, test::errorText(opened));
  // Frames until the shown structure's field is there (computed on the CPU).
  const auto end = std::chrono::steady_clock::now() + kHangGuard;
  auto fieldShown = [&] {
    const auto shown = model.explore().shown();
    return model.fields().pickField() && model.explore().fieldLabel() == shown.label && model.fields().settled();
  };
  while (!fieldShown() && std::chrono::steady_clock::now() < end) {
    model.beginFrame(nullptr);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  REQUIRE(fieldShown());
  const std::uint16_t label = model.explore().shown().label;
  const render::StructureFrame* frame = model.explore().frameOf(label);
  REQUIRE(frame);
  const double bySize = render::distanceUnitFor(*frame);
  auto unitNow = [&] { return model.renderSettings(model.scheduler().planFor(app::kFullLevel)).distanceUnit; };

  // The measure starts and blocks; renderSettings returns meanwhile with the size-based unit.
  CHECK(unitNow() == doctest::Approx(bySize));
  REQUIRE(gates.waitStarted(1));
  CHECK(unitNow() == doctest::Approx(bySize));
  model.beginFrame(nullptr);
  CHECK(unitNow() == doctest::Approx(bySize));
  CHECK_FALSE(model.idle());     // the image will still change without input
  CHECK_FALSE(model.settled());
  const int id = gates.startedIds().front();
  CHECK(id / 1000 == label);

  // Released: taken in a later frame, and the frame that takes it moves the view's revision (the
  // scheduler renders again) — the image never keeps a unit other than the settings'.
  gates.releaseAll();
  double unit = unitNow();
  while (unit != Gates::unitOf(id) && std::chrono::steady_clock::now() < end) {
    const auto revision = model.explore().revision();
    model.beginFrame(nullptr);
    const double next = unitNow();
    if (next != unit) CHECK(model.explore().revision() > revision);
    unit = next;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  CHECK(unit == Gates::unitOf(id));
  CHECK_FALSE(gates.hung);
}
