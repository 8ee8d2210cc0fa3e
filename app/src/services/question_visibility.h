// Whether each locate question of a course can be answered in its own view: the view rendered as
// the terminal draws it (400×300, framed on the region with a margin, the step's preset, camera and
// clip), a click on the middle of where the target lies in the picture (render/click_point.h: for a
// structure in two parts, the middle of the wider part) must pick the target, and context must be
// drawn where it picks. `course validate` refuses a course that fails it; tests/app/test_question_scenes.cpp
// checks the shipped courses with the same code.
#pragma once

#include <atomic>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "lessons/curriculum.h"
#include "render/derived_preset.h"
#include "render/gradient_volume.h"
#include "render/preset.h"
#include "volume/structure.h"

namespace at::app {

// How the check draws a question's view (as app/src/cli/terminal_views.h does).
constexpr int kCheckViewWidth = 400, kCheckViewHeight = 300;
constexpr double kLocateRegionMargin = 2.5;

// A student must see where she is asked to click. The target is drawn only as context of the
// region's field (it is not marked), and a preset can fade the context out entirely (a CT preset on
// plain µCT intensities draws none at any t), yet the pick still finds the target's label along the
// ray: a click on blackness where one knows it lies would be graded right, and nobody could see
// where that is. So the picture must draw context — the target, its wall or the bone around it —
// where the target picks or next to it: a pixel counts where the context's composited opacity
// reaches kShownOpacity and it picks the target or lies within kShownRingPixels of one that does (a
// cavity seen through its opening, the orbit from the front, shows its rim around those pixels, not
// on them). At least kMinShownPixels such pixels of the 400×300 view are needed (counted on every
// kShownGridStep-th pixel of each axis). The highlighted region's own surface does not count.
constexpr double kShownOpacity = 0.2;
constexpr int kShownRingPixels = 6;
constexpr int kMinShownPixels = 100;
constexpr int kShownGridStep = 2;

struct LocateCheck {
  std::string path;        // "lessons[3].steps[4].question"
  std::string questionId;
  // A click on the middle of the target picks the target, and context is drawn where it picks it.
  bool answerable = false;
  std::string problem;      // when not: what the click picks instead, why it cannot be made, or that it is not drawn
  int pickingPixels = 0;    // pixels of the view that pick the target (estimated from the grid)
  int shownPixels = 0;      // pixels at or next to those that draw context
  double clickX = 0, clickY = 0;  // the middle of the target in the view: where a student clicks it
};

// Checks locate questions on one dataset (which outlives it), keeping what the checks share — the
// intensity summary, the gradients, each region's field — between them. One check at a time: the
// checker is not safe to use from two threads at once.
class LocateViewChecker {
 public:
  explicit LocateViewChecker(const Dataset& dataset);
  // The desktop's checker, kept while `dataset` is on screen and used on a worker thread: it reads
  // `gradients` (those of dataset.volume, which both outlive the checker and stay unchanged) instead
  // of computing its own, and it reads the labels and structures given to useLabels — its own copy
  // — instead of the dataset's, which the segment editor may change while a check runs. It keeps
  // the fields of the kKeptFields regions and presets checked last (the other form keeps every one:
  // a course's check visits each once).
  static constexpr std::size_t kKeptFields = 4;
  LocateViewChecker(const Dataset& dataset, const render::GradientVolume& gradients);
  ~LocateViewChecker();
  LocateViewChecker(const LocateViewChecker&) = delete;
  LocateViewChecker& operator=(const LocateViewChecker&) = delete;

  // Checks read these labels and structures from now on (a copy of the dataset's as they are now,
  // on its grid); the fields computed on the previous ones are dropped. Not while a check runs.
  void useLabels(LabelMap labels, std::vector<Structure> structures);

  // `question` asked on `scene` drawn with `preset` (the course editor's captured one, or the
  // step's as presetForStep finds it). `path` is left empty. Errors: the region or target is not
  // in the dataset, the preset's field cannot be computed (one WDT per region and preset, CPU);
  // `cancel` set from another thread: an error of kind Cancelled soon after (within one WDT sweep
  // or one row of the view's pixels), with nothing cached from the check.
  Result<LocateCheck> check(const quiz::Question& question, const lessons::QuestionScene& scene,
                            const render::Preset& preset, const std::atomic<bool>* cancel = nullptr);
  // The dataset's intensity summary (for presets derived from it).
  const render::IntensityLevels& levels();

 private:
  const render::GradientVolume& gradients();
  // The dataset's labels and structures, or the copy given to useLabels (its volume left empty).
  const Dataset& labelled() const { return ownLabels_ ? *ownLabels_ : dataset_; }

  const Dataset& dataset_;
  const render::GradientVolume* sharedGradients_ = nullptr;
  std::optional<Dataset> ownLabels_;
  std::optional<render::IntensityLevels> levels_;
  std::optional<render::GradientVolume> gradients_;
  struct KeptField {
    FloatVolume distances;
    std::uint64_t used = 0;  // the check that last used it
  };
  std::map<std::string, KeptField> fields_;  // by region and field parameters
  std::size_t maxFields_ = 0;                // 0: no limit
  std::uint64_t checks_ = 0;
};

// Checks every locate question of `course` on `dataset` (one WDT per region structure, on the CPU).
// Errors: a structure or preset the course names is missing, a field that cannot be computed.
Result<std::vector<LocateCheck>> checkLocateQuestions(const Dataset& dataset, const lessons::Course& course,
                                                      const render::PresetLibrary& presets);

}  // namespace at::app
