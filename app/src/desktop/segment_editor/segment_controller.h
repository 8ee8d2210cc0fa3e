// The desktop's segment editor without drawing (the Segment window draws it; the UI script drives
// the same commands): an instructor labels the dataset on screen by painting seeds of two or more
// labels (background included) in a slice, growing every voxel to the label of its cheapest seed
// (segment::LabelEditor::growFromSeeds, the WDT's multi-label growth: CUDA where a GPU exists, else
// the CPU), a threshold island under a click, margins and hollowing of a structure, checking the
// result in the slice, undoing, and saving the labels — into the dataset
// store for an imported dataset, or as a label map file (NIfTI + names JSON, or Slicer .seg.nrrd).
//
// The editor starts from the dataset's own labels and structures. The growth runs on a worker
// thread (seconds at 256³ on two CPU cores; milliseconds on a GPU) that uses only the editor's kept
// growth (LabelEditor::computeGrowth), so the slice, the seeds and the other tools stay usable
// meanwhile; the 3-D view follows each edit, undo and redo (DesktopModel::showEditedLabels).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "view/grey_window.h"
#include "segment/growth_settings.h"
#include "segment/label_editor.h"
#include "volume/png_image.h"
#include "volume/slice_orientation.h"
#include "volume/structure.h"

namespace at::app {

class SegmentController {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // `database`: where imported datasets' labels are stored (outlives the controller). `events`
  // receives segment_grown, segment_edited, segment_saved, segment_undone and segment_redone.
  SegmentController(db::Database& database, EventSink events);
  ~SegmentController();
  SegmentController(const SegmentController&) = delete;
  SegmentController& operator=(const SegmentController&) = delete;

  // A dataset is on screen: the editor starts over from its labels (seeds and history dropped).
  // `dataset` stays valid until the next attach (the model calls it whenever it shows another).
  // `grown` (optional, valid as long): the volume grow from seeds, its defaults and the threshold
  // tools read, where the shown one had non-anatomy left out (services/scan_volumes.h: the scan as
  // loaded, as `anatomy-tutor segment` reads it); null: the dataset's own volume.
  void attach(const Dataset& dataset, const Volume* grown = nullptr);
  bool attached() const { return dataset_ != nullptr; }
  // Cancels a running growth and waits for it (before the volumes it reads are replaced, closing).
  void stopGrowth();
  bool windowOpen = false;

  // --- Labels: 0 is the background; others are the editor's structures -----------------------
  const std::vector<Structure>& structures() const;
  // Adds a structure and makes it the current label; errors: an empty or duplicate name.
  Result<std::uint16_t> addLabel(const std::string& name);
  // The label painted next: 0 or a structure's (an unknown value is an error naming it).
  Status setCurrentLabel(std::uint16_t label);
  std::uint16_t currentLabel() const { return current_; }
  // A label by structure id or display name, "background" for 0.
  Result<std::uint16_t> labelNamed(const std::string& name) const;
  // The instructor's review of a structure's labels (not started, in progress, completed,
  // flagged): read from the dataset store on attach for an imported dataset, set here, stored by
  // saveToStore with the structures. Never shown to students. Event segment_review {"structure",
  // "state"}. Errors: the background or an unknown label.
  db::ReviewState reviewState(std::uint16_t label) const;
  Status setReviewState(std::uint16_t label, db::ReviewState state);
  // The structure's system (browsing group); stored with "Save into the dataset".
  Status setSystem(std::uint16_t label, const std::string& system);

  // --- The slice ------------------------------------------------------------------------------
  // The slice across voxel axis 0, 1, 2 (x, y, z) at an index on it; errors name the range. The
  // picture shows it in patient orientation as the Slices window does (sliceLayout: the
  // radiological convention of volume/slice_orientation.h, its edge letters), whatever the file's
  // voxel order: a NIfTI in RAS and its DICOM series are painted on the same picture.
  Status setSlice(int axis, int index);
  // The patient layout of the current slice (its plane: the one voxel axis `axis()` crosses).
  SliceLayout sliceLayout() const;
  // The voxel axis that crosses `plane` (2 for the axial plane of an axial scan).
  int axisOfPlane(PatientPlane plane) const;
  int axis() const { return axis_; }
  int index() const { return index_; }
  int sliceCount() const;  // along the current axis
  // The middle slice across `axis` (the view switching between axial, coronal and sagittal).
  Status showAxis(int axis);
  // The size in mm of one voxel of the slice picture (columns, rows): the picture is shown at this
  // aspect, so anisotropic voxels look as they are.
  std::array<double, 2> slicePixelMm() const;
  // A right-drag of (dx, dy) pixels on the slice: the grey window as in the Slices window
  // (GreyWindow::drag); it starts at the dataset's default on attach.
  void dragWindow(double dx, double dy);
  std::array<double, 2> greyWindow() const { return grey_.centreWidth(); }
  // The slice: grey in the dragged window, labels at `labelAlpha`, seeds opaque in their label's
  // colour (background seeds white); `scale` pixels per voxel. Its pixel → voxel map is sliceVoxelAt
  // (volume/slice_image.h) with sliceLayout(), the index and the scale.
  Result<RgbImage> sliceImage(int scale, double labelAlpha = 0.45) const;
  std::optional<std::array<int, 3>> voxelAtPixel(int scale, double x, double y) const;
  // Changes whenever the slice picture would (labels, seeds, slice).
  std::uint64_t revision() const { return revision_; }
  // Changes whenever the labels or the structures may have changed (an edit, a growth applied,
  // undo, redo, a structure added).
  std::uint64_t labelsRevision() const { return labelsRevision_; }

  // --- Seeds and tools ------------------------------------------------------------------------
  // The brush's radius (seeds, paint, erase); 0: the voxel alone. 1.5 mm on CT and a 0.1 mm µCT;
  // on a finer µCT it is kept voxel for voxel (times fineVoxelScale, volume/geometry.h): attach
  // rescales it from one dataset's scale to the next.
  double brushMm = 1.5;
  // fineVoxelScale of the attached dataset's largest spacing (1: none): the Segment window's
  // lengths (brush, margin, bridges) are kept voxel for voxel with it.
  double brushScale() const { return brushScale_; }
  // With a seed range (the dataset's values), a click seeds only the voxels of the brush's ball
  // whose values lie in it and join the clicked voxel through such voxels: a local threshold, for
  // any label — one large background dab in the air beside a thin bone seeds the air, not the bone
  // (segment/local_threshold.h). nullopt: the whole ball.
  std::optional<std::array<double, 2>> seedRange;
  // Seeds of the current label in the ball of brushMm around the voxel's centre (later seeds
  // replace earlier ones), limited by seedRange. Returns the number of voxels seeded. Errors: a
  // voxel outside the grid; with a seed range, the value under the voxel outside it.
  Result<std::size_t> paintSeeds(const std::array<int, 3>& voxel);
  void clearSeeds();
  std::size_t seedCount() const { return seeds_.size(); }
  // Seed voxels per label.
  std::map<std::uint16_t, std::size_t> seedsPerLabel() const;
  // Every voxel to the label of its cheapest seed, grown on a worker thread so that the window
  // stays responsive: starts a growth with the seeds painted now and returns. Asked again while
  // one runs, that one is cancelled between rounds and a growth with the latest seeds follows
  // (latest wins: only its result is applied). poll() applies a finished growth as one edit
  // (event segment_grown; the slice shows it). Incremental after the first growth. Errors, at
  // once: seeds of fewer than two labels (naming the one seeded); the growth's own errors come
  // through growError() once it ends.
  Status grow();
  bool growing() const { return job_ != nullptr; }

  // The growth's settings, from segment::defaultGrowthSettings on attach (the data's window and a
  // base from its step noise and voxel size). The base is shown per voxel (the same meaning on
  // every grid); the window in the dataset's values (HU or intensities). setGrowthSettings checks
  // them (errors name the field) and, when a growth has been grown or is running, grows again
  // with them at once: the slice previews the new settings (latest wins, as for seeds).
  struct GrowthSettings {
    double basePerVoxel = 0;
    std::array<double, 2> window{0, 1};
    double smoothingVoxels = 0;
    bool limitRange = false;             // "bone only": grow only into values in `range`
    std::array<double, 2> range{0, 0};   // in the dataset's values; defaults to its bone range
  };
  const GrowthSettings& growthSettings() const { return settings_; }
  const segment::GrowthDefaults& growthDefaults() const { return defaults_; }
  Status setGrowthSettings(const GrowthSettings& settings);
  void resetGrowthSettings();  // back to the data's defaults (grows again like setGrowthSettings)
  GrowthParams growthParams() const;  // what the next growth runs with

  // A label's own grow range, as a seeds file's "grow_range" (segment/ranged_growth.h): the label
  // keeps only voxels whose value lies in the range, taken by a growth that cannot leave it, so a
  // thin bone is not padded with the soft tissue and air around it. `bone`: the data's bone range
  // (growthDefaults().boneRangeValues); else `values` in the dataset's values (HU or intensities).
  // Every growth applies them exactly as `anatomy-tutor segment --seeds` does (one library path:
  // LabelEditor::computeGrowth with segment::LabelRanges); saveSeeds writes them, loadSeeds takes a
  // file's. Setting or clearing one (nullopt) grows again when a growth is on screen. Event
  // segment_label_range {"label", "range": [lo, hi] | null, "bone"}. Errors: the background, an
  // unknown label, values not low < high.
  struct LabelGrowRange {
    std::optional<std::array<double, 2>> values;
    bool bone = false;
  };
  Status setLabelGrowRange(std::uint16_t label, std::optional<LabelGrowRange> range);
  std::optional<LabelGrowRange> labelGrowRange(std::uint16_t label) const;
  // The ranges the next growth applies, "bone" resolved (empty: the ordinary growth alone).
  segment::LabelRanges labelRanges() const;

  // Seeds as a seeds file (segment/seeds.h): each row of seed voxels of one label a stroke of
  // radius 0 between its end voxels' centres (LPS mm; it rasterises to exactly those voxels), the
  // labels by name (the background and the structures seeded), and the growth settings — what
  // `anatomy-tutor segment --seeds` grows the same labels from. loadSeeds replaces the painted
  // seeds with a file's (strokes rasterised on this grid), adds the structures it names that the
  // editor lacks, and takes its grow settings; returns the seed voxels. Errors name the file.
  Status saveSeeds(const std::string& path) const;
  Result<std::size_t> loadSeeds(const std::string& path);
  // The last growth's error, if it failed (cleared by the next grow()).
  const std::optional<Error>& growError() const { return growError_; }
  // Each frame: applies a finished growth, or starts the one asked for since.
  void poll();
  // Undo reverts the newest edit, redo re-applies the newest undone one (the editor's history of
  // compressed label changes); a new edit drops what could be redone. Errors (NotFound): nothing
  // to undo / redo. Events segment_undone / segment_redone {"edit": description}.
  Result<std::string> undo();
  Result<std::string> redo();
  bool canUndo() const { return editor_ && editor_->history().canUndo(); }
  bool canRedo() const { return editor_ && editor_->history().canRedo(); }
  const LabelMap& labels() const;

  // --- The click's tool: in the slice, and for paint / erase also on the 3-D view's surface ----
  enum class Tool { Seeds, Threshold, Paint, Erase };
  Tool tool = Tool::Seeds;
  // Whether a click or drag in the 3-D view paints: the window is open with paint or erase.
  bool brushesInView() const { return windowOpen && attached() && (tool == Tool::Paint || tool == Tool::Erase); }
  // One dab of the tool's sphere brush (brushMm) around a point in LPS mm — a slice voxel's
  // centre, or where a 3-D pick met the volume: paint the current structure (not the background)
  // or erase every label. Event segment_edited {"tool": "paint"/"erase", "point_mm", "radius_mm"}.
  // Errors: another tool, painting the background, a point outside the grid.
  Result<segment::EditSummary> brushAt(const Vec3& pointMm);
  Result<segment::EditSummary> brushAtVoxel(const std::array<int, 3>& voxel);
  // A drag's dabs between these are one edit (one undo): the window's mouse down and up.
  void beginStroke();
  void endStroke();

  // --- Tools on the current label (a structure: the background is not grown or hollowed) -----
  // The connected region under `voxel` of values in [low, high] (the dataset's units: HU or plain
  // intensities) takes the current label (labelled voxels of other structures are kept);
  // minDiameterMm > 0 cuts bridges thinner than it. Errors: background current, an empty range,
  // a voxel outside the grid or outside the range.
  Result<segment::EditSummary> thresholdIsland(const std::array<int, 3>& voxel, double low, double high,
                                               double minDiameterMm);
  // The current structure grown (mm > 0, onto unlabelled voxels) or shrunk (mm < 0).
  Result<segment::EditSummary> margin(double mm);
  // The current structure keeps a shell of `thicknessMm` inside its surface.
  Result<segment::EditSummary> hollow(double thicknessMm);
  // The current structure's pieces (bridges thinner than minDiameterMm cut; pieces of at least
  // minVoxels) become structures of their own (segment::LabelEditor::splitIslands); the largest
  // stays current.
  Result<segment::IslandSplit> splitIslands(double minDiameterMm, std::size_t minVoxels);
  // The range a threshold starts from: the dataset's window, in its units.
  std::array<double, 2> valueWindow() const;

  // --- Saving ---------------------------------------------------------------------------------
  // Into the dataset store (the dataset must be an imported one); returns the stored file.
  Result<std::string> saveToStore();
  // As a file (checkLabelsPath), with a names JSON beside a NIfTI when `namesPath` is not empty.
  Status exportLabels(const std::string& path, const std::string& namesPath);

  const std::string& status() const { return status_; }

 private:
  Status requireDataset() const;
  Result<std::string> stepHistory(bool forward);  // undo (false) or redo (true)
  Status startGrowth();  // with the seeds painted now, on a worker thread
  Status requireStructureCurrent(const std::string& tool) const;
  // After an edit: the slice is redrawn, the status says what changed, and an event
  // {"event": kind, "tool": tool, "changed": n, "voxels": {structure: count}} is sent.
  // A brush dab leaves the voxel counts out (a pass over the whole map for each dab of a drag).
  void edited(const std::string& kind, const std::string& tool, const segment::EditSummary& summary,
              nlohmann::json extra = nlohmann::json::object(), bool countVoxels = true);
  db::Database& database_;
  EventSink events_;
  const Dataset* dataset_ = nullptr;  // the dataset being labelled (its volume and intensity)
  const Volume* grown_ = nullptr;     // what growth and thresholds read (attach), never null once attached
  std::unique_ptr<segment::LabelEditor> editor_;
  std::map<std::size_t, std::uint16_t> seeds_;  // voxel index → label
  // Per-label grow ranges (setLabelGrowRange, or a loaded seeds file's "grow_range"), by editor
  // label, in the order they were given (the seeds file's: ranged_growth.h's rule takes the first
  // range that claims a voxel).
  std::vector<std::pair<std::uint16_t, LabelGrowRange>> growRanges_;
  db::ReviewStates review_;                     // by structure id
  std::uint16_t current_ = 0;
  int axis_ = 2, index_ = 0;
  GreyWindow grey_;
  std::uint64_t revision_ = 0;
  std::uint64_t labelsRevision_ = 0;
  std::string status_;
  struct GrowJob;
  std::unique_ptr<GrowJob> job_;  // the growth running on its worker, until poll() takes it
  bool growAgain_ = false;        // seeds changed and grow was asked while job_ ran
  std::optional<Error> growError_;
  segment::GrowthDefaults defaults_;
  GrowthSettings settings_;
  double brushScale_ = 1.0;
  bool grownOnce_ = false;  // a growth was started since attach (settings changes preview)
};

}  // namespace at::app
