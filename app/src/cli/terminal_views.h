// What `play` and `exam` show in a terminal: every view a step or question refers to is written as
// a PNG through the offscreen renderer (as `render` does) and its path printed; a locate answer is a
// pick on that picture — a pixel, turned into the structure under it by the same picking code the
// desktop uses (render::pickStructure), or a point in millimetres — never a typed name. Pictures
// carry pixel rulers along their top and left edges (ticks every 10 px, numbers every 100).
#pragma once

#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "db/connection.h"
#include "lessons/curriculum.h"
#include "quiz/question.h"
#include "render/gradient_volume.h"
#include "render/preset.h"
#include "render/render_settings.h"
#include "render/scene.h"
#include "volume/slice_image.h"
#include "volume/structure.h"
#include "render/derived_preset.h"
#include "render/gradient_volume.h"
#include "wdt/wdt.h"

namespace at::render::gl {
class EglContext;
class VolumeRenderer;
}  // namespace at::render::gl

namespace at::app {

inline constexpr int kPictureWidth = 400, kPictureHeight = 300;  // software GL: about 2 s a picture
inline constexpr double kRegionMargin = 2.5;

// A picture written for the student, and how a pick on it is read.
struct TerminalPicture {
  std::string path;
  int width = 0;
  int height = 0;
  bool slice = false;  // a CT slice (pixel → voxel) rather than a 3-D view (pixel → ray)
};

// Picks on one picture for one target, worked out once (PixelPicks::at changes nothing, so several
// threads may pick at once: a locate key picks every pixel). Made by TerminalViews::pixelPicks;
// valid until that object shows or frames its next picture.
class PixelPicks {
 public:
  // The structure under pixel (x, y) and the weighted distance in mm from the target to the
  // picked point (−1 when it could not be measured), as TerminalViews::pickPixel.
  Result<quiz::Pick> at(double x, double y) const;

 private:
  friend class TerminalViews;
  const Dataset* dataset_ = nullptr;
  const SliceRequest* slice_ = nullptr;                // a slice picture, or
  const render::RenderSettings* settings_ = nullptr;  // a 3-D picture with
  const render::TransferFunction2D* table_ = nullptr;
  render::SceneVolumes volumes_;
  const Structure* target_ = nullptr;      // null: no such structure (no distance)
  const FloatVolume* targetField_ = nullptr;  // null: distance unknown
};

class TerminalViews {
 public:
  // Pictures of `datasetId` (the built-in phantom is drawn at 128³: the same anatomy, 0.4 mm
  // voxels) written into `dir` (created). Without `pictures` only the dataset is loaded (points in
  // mm can still be picked). Errors: the dataset does not load, no offscreen GL.
  static Result<std::unique_ptr<TerminalViews>> create(db::Database& db, const std::string& datasetId,
                                                       std::filesystem::path dir, bool pictures = true);
  bool pictures() const { return renderer_ != nullptr; }
  ~TerminalViews();
  TerminalViews(const TerminalViews&) = delete;
  TerminalViews& operator=(const TerminalViews&) = delete;

  // The 3-D view of `scene` (its structure selected and framed, its preset, its side) as
  // dir/stem.png, kPictureWidth × kPictureHeight. `region`: frame a wider region (the structure's
  // extent times kRegionMargin fills the view instead of render's default), as locate questions do. With
  // `visibleTarget`, the side is the first of the scene's own and the other named views from which
  // a click on the target's centre picks the target.
  Result<TerminalPicture> show(const lessons::QuestionScene& scene, const std::string& stem, bool region = false,
                               const std::optional<std::string>& visibleTarget = std::nullopt);
  // The view show() would draw (same arguments), made the one picks are read on without drawing it
  // (pictures may be off; the returned picture has no path): what a locate key is worked out on.
  Result<TerminalPicture> frame(const lessons::QuestionScene& scene, bool region = false,
                                const std::optional<std::string>& visibleTarget = std::nullopt);
  // The id of the last 3-D view (empty after a slice or before any view): equal on two machines
  // exactly when a pixel picks the same there — the same size, camera, clip, preset, selected
  // structure, sampling and dataset voxels. A class server grades a lesson's locate pixel by it.
  std::string lastViewId();

  // An axial CT slice through the target's centre, without labels, as dir/stem.png; with
  // `highlight` ("show me on a slice") the target alone overlaid in its colour.
  Result<TerminalPicture> showSlice(const std::string& target, const std::string& stem, bool highlight = false);

  // The structure under pixel (x, y) of the last picture, with the weighted distance in mm from
  // `target` to the picked point (for tolerance bands; −1 when it could not be measured).
  Result<quiz::Pick> pickPixel(double x, double y, const std::string& target);
  // Picks on the last picture for `target` (its field computed now if it was not yet), for many
  // pixels or several threads. Error: no picture yet.
  Result<PixelPicks> pixelPicks(const std::string& target);
  // The pixels (x0, y0, x1, y1 inclusive; x1 < x0 when none) of the last 3-D view outside which no
  // pick is graded right for `target` with `toleranceMm`: the projection of the target's voxels and
  // of its field's voxels within the tolerance, each grown by a voxel (render::pixelsThatCanPick).
  // nullopt: any pixel may (a slice, or a box reaching behind the eye).
  std::optional<std::array<int, 4>> pixelsThatCanPick(const std::string& target, double toleranceMm);
  // The structure at a point in patient LPS millimetres.
  Result<quiz::Pick> pickPointMm(const Vec3& pointMm, const std::string& target);

  const Dataset& dataset() const { return dataset_; }

 private:
  TerminalViews() = default;
  Result<const FloatVolume*> fieldOf(const Structure& structure, const render::Preset& preset);
  // The scene's view framed on `view` (its camera and plane put in), the unit from `field` (when
  // given) on that view: course_views.h stepViewSettings.
  Result<render::RenderSettings> settingsFor(const Structure& selected, const render::Preset& preset,
                                             const lessons::QuestionScene& scene, const std::string& view, int width,
                                             int height, double margin, const FloatVolume* field);
  // The scene's preset, else the structure's shipped or derived WDT preset.
  Result<render::Preset> presetOf(const Structure& structure, const std::string& presetId) const;
  // The target's field for distances of picks (computed once); null when it cannot be had.
  const FloatVolume* pickFieldOf(const Structure& target);

  Dataset dataset_;
  render::IntensityLevels levels_;    // derived presets where none is shipped
  std::filesystem::path dir_;
  std::unique_ptr<render::PresetLibrary> presets_;
  db::Database* database_ = nullptr;  // its presets come before the library's (course_views.h)
  std::unique_ptr<render::gl::EglContext> context_;
  std::unique_ptr<render::gl::VolumeRenderer> renderer_;
  std::map<std::string, FloatVolume> fields_;  // WDT per structure id, computed once
  std::map<std::uint16_t, render::SelectedMask> masks_;  // smoothed mask per selected label, for picks
  std::unique_ptr<render::GradientVolume> gradients_;  // of the volume, for picking as the desktop does

  // What the last picture showed, for picks on it.
  std::optional<render::RenderSettings> lastSettings_;
  std::optional<render::TransferFunction2D> lastTable_;  // shadingTable(lastSettings_->preset)
  std::uint16_t lastSelected_ = 0;
  const FloatVolume* lastField_ = nullptr;
  std::optional<SliceRequest> lastSlice_;
  std::optional<std::uint64_t> dataDigest_;  // of the volume's and labels' voxels, for lastViewId
};

// The pictures of a terminal run: none when `off` (--no-views), else written into `dir` (default
// ./anatomy-tutor-views). When they cannot be made a one-line note says why and the run goes on
// without them (locate answers are then points in mm). Null only when the dataset does not load.
std::unique_ptr<TerminalViews> openTerminalViews(db::Database& db, const std::string& datasetId,
                                                 const std::optional<std::string>& dir, bool off);

// Where a terminal answer points: a pixel of the last picture or a point in mm.
struct PickInput {
  std::optional<std::array<double, 2>> pixel;
  std::optional<Vec3> pointMm;
};
// Reads "x y" / "x,y" (a pixel) or "mm X Y Z" (a point in LPS mm). Errors explain both forms.
Result<PickInput> parsePickInput(const std::string& text);

}  // namespace at::app
