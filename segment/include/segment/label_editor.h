// The segment editor's model (ARCHITECTURE.md §1, segment/): a label map and its structures, the
// tools an instructor labels with — all in millimetres on the dataset's grid, anisotropic spacing
// included — and undo/redo of every edit as compressed changes (label_history.h).
//
// Tools:
//   paint / erase           a sphere brush around a point in mm (a stroke of dabs: one edit)
//   thresholdIsland         the connected region of voxels in a value range under a point; with a
//                           minimum diameter, bridges thinner than it are cut (opening by a ball)
//   growFromSeeds           every voxel takes the label of its cheapest seed (wdt/label_growth.h);
//                           the growth is kept, so re-running it after seed edits is incremental
//   margin                  grow (mm > 0, onto unlabelled voxels) or shrink (mm < 0) a structure
//   hollow                  keep a shell of a thickness inside a structure's surface (at least
//                           one voxel: the grid's largest spacing)
//   smooth                  opening (removes specks and spurs) or closing (fills gaps and holes)
//   splitIslands            a structure's disconnected pieces (after cutting bridges thinner than a
//                           diameter) become structures of their own (label_islands.cpp)
//   structures              add, rename, colour, delete (the last clears its voxels)
// Edits that change nothing are not recorded. Values of a threshold range are the dataset's (HU or
// plain intensities: IntensityModel::valueOf).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "segment/label_history.h"
#include "segment/ranged_growth.h"
#include "volume/structure.h"
#include "wdt/label_growth.h"

namespace at::segment {

struct EditSummary {
  std::string description;     // "paint liver: 1,234 voxels"
  std::size_t changed = 0;     // voxels whose label changed
  std::size_t historyBytes = 0;  // the whole history's compressed size after the edit
};

enum class Smoothing { Opening, Closing };

struct IslandSplit {
  EditSummary summary;
  std::vector<std::uint16_t> newLabels;  // the new structures' labels, largest piece first
};

struct ThresholdOptions {
  double minDiameterMm = 0;  // 0: no bridge cutting
  bool overwrite = false;    // false: only unlabelled voxels (and the structure's own) take the label
};

class LabelEditor {
 public:
  // Edits `labels` (the dataset's, or an empty map on its grid) with these structures.
  LabelEditor(LabelMap labels, std::vector<Structure> structures);
  ~LabelEditor();
  LabelEditor(LabelEditor&&) noexcept;
  LabelEditor& operator=(LabelEditor&&) noexcept;

  const LabelMap& labels() const { return labels_; }
  const std::vector<Structure>& structures() const { return structures_; }
  const LabelHistory& history() const { return history_; }

  // Structures. add returns the new label (one above the largest in use); names must be unique and
  // non-empty. Errors name the structure.
  Result<std::uint16_t> addStructure(const std::string& name, std::optional<std::array<float, 3>> colour = {});
  Status renameStructure(std::uint16_t label, const std::string& name);
  Status setColour(std::uint16_t label, std::array<float, 3> colour);
  // The structure's browsing group ("middle ear", "skull bones"; empty: none), trimmed; undoable.
  Status setSystem(std::uint16_t label, const std::string& system);
  Result<EditSummary> deleteStructure(std::uint16_t label);

  // Tools. Points are LPS mm; a point or a whole sphere outside the grid is an error naming it.
  Result<EditSummary> paint(const Vec3& centreMm, double radiusMm, std::uint16_t label);
  // Erases `only` (or every label when nullopt) inside the sphere.
  Result<EditSummary> erase(const Vec3& centreMm, double radiusMm, std::optional<std::uint16_t> only = {});
  Result<EditSummary> thresholdIsland(const Volume& volume, const IntensityModel& intensity, const Vec3& pointMm,
                                      double low, double high, std::uint16_t label, const ThresholdOptions& options = {});
  // Relabels every voxel from the seeds (GrowthSeed labels are label values; 0 is background).
  // The growth is kept between calls with the same volume and params: the next call recomputes
  // only what the seed changes affect. `stats` (optional) receives the growth's statistics. With
  // per-label `ranges` (a seeds file's "grow_range"), the labels are ranged_growth.h's rule over
  // that growth (its limited growths kept between calls too).
  Result<EditSummary> growFromSeeds(const Volume& volume, const std::vector<GrowthSeed>& seeds,
                                    const GrowthParams& params, GrowthStats* stats = nullptr,
                                    const LabelRanges& ranges = {});
  // growFromSeeds in two halves, for a caller that grows on a worker thread: computeGrowth uses
  // only the kept growth (not the labels, structures or history), so another thread may read and
  // edit the labels meanwhile; commitGrowth then applies the grown labels as one edit (on the
  // labels' thread). No two computeGrowth at once, and no commitGrowth while one runs.
  // `control.cancel` stops it between rounds (stats.cancelled; commit nothing then: the next
  // computeGrowth finishes the work left).
  Result<GrowthStats> computeGrowth(const Volume& volume, const std::vector<GrowthSeed>& seeds, const GrowthParams& params,
                                    const WdtControl& control = {}, const LabelRanges& ranges = {});
  Result<EditSummary> commitGrowth(std::size_t seedCount);
  Result<EditSummary> margin(std::uint16_t label, double mm);
  Result<EditSummary> hollow(std::uint16_t label, double thicknessMm);
  Result<EditSummary> smooth(std::uint16_t label, Smoothing operation, double radiusMm);
  // Splits a structure into its pieces: the 6-connected parts of its voxels, with minDiameterMm > 0
  // after cutting bridges thinner than that (opening by a ball of that diameter, as
  // thresholdIsland). The largest piece keeps the structure; every other piece of at least
  // minVoxels voxels becomes a new structure "NAME (2)", "NAME (3)", … by size, with the
  // structure's system; voxels in no such piece (the bridges, smaller pieces) keep the structure.
  // One edit: undo restores the labels and the structure list. Errors: an unknown label, no
  // second piece of minVoxels voxels (the message gives the pieces' count and largest sizes).
  Result<IslandSplit> splitIslands(std::uint16_t label, double minDiameterMm = 0, std::size_t minVoxels = 1);

  // A brush stroke: the edits between beginStroke and endStroke (paint and erase dabs along a
  // drag) become one edit, one undo. endStroke returns its summary (nullopt: nothing changed).
  // An edit of the structure list ends a stroke first. A second beginStroke ends the first.
  void beginStroke();
  std::optional<EditSummary> endStroke();
  bool inStroke() const { return stroke_.has_value(); }

  // Undo/redo the newest edit; returns its description. Error (NotFound) when there is none.
  Result<std::string> undo();
  Result<std::string> redo();

 private:
  const Structure* find(std::uint16_t label) const;
  Status requireStructure(std::uint16_t label) const;
  // Applies new labels to the voxels of `changes` (index, new label; sorted, unique) and records
  // them (with the structure lists, when given).
  EditSummary commit(const std::string& description, const std::vector<std::pair<std::size_t, std::uint16_t>>& changes,
                     std::optional<std::vector<Structure>> structuresBefore = {});
  EditSummary commitMask(const std::string& description, const Mask& mask, std::uint16_t value,
                         std::optional<std::uint16_t> onlyWhere = {});

  LabelMap labels_;
  std::vector<Structure> structures_;
  LabelHistory history_;
  struct Growth;
  std::unique_ptr<Growth> growth_;
  struct Stroke {
    std::size_t edits = 0;
    std::string tool;  // the first dab's description, without its count
  };
  std::optional<Stroke> stroke_;
};

}  // namespace at::segment
