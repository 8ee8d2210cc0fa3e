#include "question_visibility.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/parallel_rows.h"
#include "course_views.h"
#include "render/click_point.h"
#include "render/derived_preset.h"
#include "render/gradient_volume.h"
#include "render/pick_bounds.h"
#include "render/scene.h"
#include "render/structure_pick.h"
#include "volume/mask.h"
#include "wdt/field_service.h"
#include "wdt/wdt.h"

namespace at::app {
namespace {

bool isSet(const std::atomic<bool>* flag) { return flag && flag->load(std::memory_order_relaxed); }

tl::unexpected<Error> cancelled() { return fail(ErrorKind::Cancelled, "the locate view check was cancelled"); }

// Counts, on a grid of every kShownGridStep-th pixel, the pixels that pick the target and, of those
// and the pixels within kShownRingPixels of them, the ones that draw context (render::contextOpacity
// ≥ kShownOpacity) — rows on all cores. False when `cancel` was set meanwhile (the rows left after
// it are skipped and `check` is not filled in).
bool countShownPixels(const render::SceneVolumes& volumes, const render::RenderSettings& settings,
                      const render::TransferFunction2D& table, std::uint16_t target, LocateCheck& check,
                      const std::atomic<bool>* cancel) {
  const auto box = render::pixelsThatCanPick(*volumes.labels, target, nullptr, 0, settings);
  const int x0 = box ? std::max(0, (*box)[0] - kShownRingPixels) : 0;
  const int y0 = box ? std::max(0, (*box)[1] - kShownRingPixels) : 0;
  const int x1 = box ? std::min(settings.width - 1, (*box)[2] + kShownRingPixels) : settings.width - 1;
  const int y1 = box ? std::min(settings.height - 1, (*box)[3] + kShownRingPixels) : settings.height - 1;
  if (x1 < x0 || y1 < y0) return true;
  const int cols = (x1 - x0) / kShownGridStep + 1, rows = (y1 - y0) / kShownGridStep + 1;
  std::vector<char> picks(std::size_t(cols) * std::size_t(rows), 0);
  forEachRowInParallel(rows, [&](int row) {
    if (isSet(cancel)) return;
    for (int col = 0; col < cols; ++col)
      picks[std::size_t(row) * std::size_t(cols) + std::size_t(col)] =
          render::pickStructure(volumes, settings, table, x0 + col * kShownGridStep, y0 + row * kShownGridStep).label ==
          target;
  });
  // The cells within the ring of a picking cell (a square ring: Chebyshev distance), then which of
  // them draw context (marched only there).
  const int ring = kShownRingPixels / kShownGridStep;
  if (isSet(cancel)) return false;
  std::vector<char> near(picks.size(), 0);
  for (int row = 0; row < rows; ++row)
    for (int col = 0; col < cols; ++col) {
      if (!picks[std::size_t(row) * std::size_t(cols) + std::size_t(col)]) continue;
      for (int r = std::max(0, row - ring); r <= std::min(rows - 1, row + ring); ++r)
        for (int c = std::max(0, col - ring); c <= std::min(cols - 1, col + ring); ++c)
          near[std::size_t(r) * std::size_t(cols) + std::size_t(c)] = 1;
    }
  std::vector<char> shows(picks.size(), 0);
  forEachRowInParallel(rows, [&](int row) {
    if (isSet(cancel)) return;
    for (int col = 0; col < cols; ++col) {
      const std::size_t i = std::size_t(row) * std::size_t(cols) + std::size_t(col);
      if (near[i])
        shows[i] = render::contextOpacity(volumes, settings, table, x0 + col * kShownGridStep,
                                          y0 + row * kShownGridStep) >= kShownOpacity;
    }
  });
  if (isSet(cancel)) return false;
  int picking = 0, shown = 0;
  for (std::size_t i = 0; i < picks.size(); ++i) {
    picking += picks[i];
    shown += shows[i];
  }
  check.pickingPixels = picking * kShownGridStep * kShownGridStep;
  check.shownPixels = shown * kShownGridStep * kShownGridStep;
  return true;
}

}  // namespace

LocateViewChecker::LocateViewChecker(const Dataset& dataset) : dataset_(dataset) {}

LocateViewChecker::LocateViewChecker(const Dataset& dataset, const render::GradientVolume& gradients)
    : dataset_(dataset), sharedGradients_(&gradients), maxFields_(kKeptFields) {}

LocateViewChecker::~LocateViewChecker() = default;

void LocateViewChecker::useLabels(LabelMap labels, std::vector<Structure> structures) {
  Dataset own;
  own.id = dataset_.id;
  own.labels = std::move(labels);
  own.structures = std::move(structures);
  ownLabels_ = std::move(own);
  fields_.clear();  // each region's field grew from its voxels as they were
}

const render::GradientVolume& LocateViewChecker::gradients() {
  if (sharedGradients_) return *sharedGradients_;
  if (!gradients_) gradients_ = render::computeGradientVolume(dataset_.volume);
  return *gradients_;
}

const render::IntensityLevels& LocateViewChecker::levels() {
  if (!levels_) levels_ = render::summariseIntensities(dataset_.volume);
  return *levels_;
}

Result<LocateCheck> LocateViewChecker::check(const quiz::Question& question, const lessons::QuestionScene& scene,
                                             const render::Preset& preset, const std::atomic<bool>* cancel) {
  LocateCheck check;
  check.questionId = question.id;
  const Dataset& labelled = this->labelled();
  const Structure* region = labelled.findStructure(scene.structure);
  const Structure* target = labelled.findStructure(question.target);
  if (!region || !target)
    return fail("no structure '" + (region ? question.target : scene.structure) + "' in dataset '" + dataset_.id + "'");
  if (isSet(cancel)) return cancelled();
  const render::GradientVolume& gradients = this->gradients();
  auto params = render::wdtParamsFor(preset);
  if (!params) return tl::unexpected(params.error());
  // One field per region and field parameters (the preset sets the field's weights; the desktop's
  // presets can be edited under the same id, so the id alone does not name the field).
  const std::string fieldKey = wdt::FieldRequest{region->label, *params}.key();
  ++checks_;
  if (!fields_.count(fieldKey)) {
    WdtControl control;
    control.cancel = cancel;
    auto wdt = computeWdt(dataset_.volume, structureMask(labelled.labels, region->label), *params, control);
    if (!wdt) return tl::unexpected(withContext("field of '" + region->id + "'", wdt.error()));
    if (wdt->stats.cancelled || isSet(cancel)) return cancelled();  // a partial field is not kept
    if (maxFields_ > 0 && fields_.size() >= maxFields_)
      fields_.erase(std::min_element(fields_.begin(), fields_.end(),
                                     [](const auto& a, const auto& b) { return a.second.used < b.second.used; }));
    fields_[fieldKey].distances = std::move(wdt->field.distances);
  }
  KeptField& kept = fields_.at(fieldKey);
  kept.used = checks_;
  const FloatVolume& field = kept.distances;
  auto frame = render::structureFrame(labelled.labels, region->label);
  const bool targetHasVoxels =
      std::find(labelled.labels.voxels.begin(), labelled.labels.voxels.end(), target->label) != labelled.labels.voxels.end();
  if (!frame || !targetHasVoxels) {
    check.problem = "the target or its region has no voxels";
    return check;
  }
  render::ViewRequest request;
  request.width = kCheckViewWidth;
  request.height = kCheckViewHeight;
  const std::string viewName = lessons::toString(scene.view);
  request.view = viewName;
  request.margin = kLocateRegionMargin;
  // The view (and its field's distance unit) as play and the desktop show it.
  const render::PictureInputs picture{&labelled.labels, region->label, &gradients};
  auto settings = stepViewSettings(preset, *frame, request, scene.camera, scene.clip, &field, dataset_.volume, &picture);
  if (!settings) return tl::unexpected(settings.error());
  // Where a student clicks it: the middle of where it lies in the picture (render/click_point.h).
  const auto middle = render::middleOfStructure(labelled.labels, target->label, settings->camera, kCheckViewWidth,
                                                kCheckViewHeight, settings->clip, kShownGridStep);
  if (!middle) {
    check.problem = "the " + target->id + " lies outside the view (" + viewName + ")";
    return check;
  }
  check.clickX = middle->x;
  check.clickY = middle->y;
  const std::array<double, 2> px{middle->x, middle->y};
  // The region's smoothed mask worked out once for the view's thousands of picks (the same numbers
  // as smoothing it per sample).
  const render::SelectedMask mask = render::selectedMask(labelled.labels, region->label);
  const render::SceneVolumes volumes{&dataset_.volume, &labelled.labels, &field, region->label, &gradients, &mask};
  const render::TransferFunction2D table = render::shadingTable(settings->preset);
  const render::PickResult clicked = render::pickStructure(volumes, *settings, table, px[0], px[1]);
  if (clicked.label != target->label) {
    const Structure* picked = clicked.hit ? labelled.findStructureByLabel(clicked.label) : nullptr;
    check.problem = "a click on the middle of the " + target->id + " in its view (" + viewName + ", region " + region->id +
                    ", pixel " + std::to_string(int(px[0])) + ", " + std::to_string(int(px[1])) + " of " +
                    std::to_string(kCheckViewWidth) + " × " + std::to_string(kCheckViewHeight) + ") picks " +
                    (picked ? "the " + picked->id : std::string("nothing"));
    return check;
  }
  if (!countShownPixels(volumes, *settings, table, target->label, check, cancel)) return cancelled();
  check.answerable = check.shownPixels >= kMinShownPixels;
  if (!check.answerable)
    check.problem = "the " + target->id + " is not drawn in its view (" + viewName + ", region " + region->id +
                    ", preset " + preset.id.value_or(scene.presetId) + "): " + std::to_string(check.shownPixels) +
                    " pixels at or next to the " + std::to_string(check.pickingPixels) +
                    " that pick it draw anything (at least " + std::to_string(kMinShownPixels) +
                    " must): choose a view, region or preset in which it is seen, or raise the preset's t";
  return check;
}

Result<std::vector<LocateCheck>> checkLocateQuestions(const Dataset& dataset, const lessons::Course& course,
                                                      const render::PresetLibrary& presets) {
  std::vector<LocateCheck> out;
  LocateViewChecker checker(dataset);
  for (std::size_t li = 0; li < course.lessons.size(); ++li) {
    const lessons::Lesson& lesson = course.lessons[li];
    for (std::size_t si = 0; si < lesson.steps.size(); ++si) {
      const lessons::Step& step = lesson.steps[si];
      if (step.kind != lessons::StepKind::Question || step.question.kind != quiz::QuestionKind::Locate) continue;
      const std::string path = "lessons[" + std::to_string(li) + "].steps[" + std::to_string(si) + "].question";
      const lessons::QuestionScene scene = lessons::sceneFor(step);
      if (!dataset.findStructure(scene.structure) || !dataset.findStructure(step.question.target))
        return fail(path + ": no structure '" + (dataset.findStructure(scene.structure) ? step.question.target : scene.structure) +
                    "' in dataset '" + dataset.id + "'");
      auto preset = presetForStep(presets, scene.structure, scene.presetId, checker.levels());
      if (!preset) return tl::unexpected(withContext(path, preset.error()));
      auto check = checker.check(step.question, scene, *preset);
      if (!check) return tl::unexpected(withContext(path, check.error()));
      check->path = path;
      out.push_back(std::move(*check));
    }
  }
  return out;
}

}  // namespace at::app
