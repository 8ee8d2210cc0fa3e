// The distance unit of a field, in the field's own (weighted millimetre) units, derived from the
// field and the data rather than from the structure's size.
//
// Why: a weighted distance D sums weight × path length, and the weight is small in air and soft
// tissue (the preset's base plus the HU window's share). How large D gets for the bone a user sees
// around a structure depends on the voxel size, the window, the tissue in between and the scan —
// on a 0.1 mm phantom the bone in view lies at D ≈ 1…8, on a 1 mm head CT the whole framed view
// lies within D ≈ 1 of the mandible. A unit fixed in millimetres (or taken from the structure's
// size) puts every voxel of a real scan in the distance TF's "near" band, so t does nothing.
//
// The unit (and offset, see kFarQuantileX): the context voxels are the field's voxels within the framed view's reach of the
// structure (a sphere about its centroid of radius margin × its radius, at least minRadiusMm)
// that are bone surfaces as the preset's data TF draws it (stored value at or above the level
// where the data TF reaches half its peak opacity, with a 6-neighbour below it: only surfaces are
// drawn), lie inside the body (when a body mask is given: the CT table and headrest are no context), are reachable (finite D) and are not the structure (D > 0).
// The unit is their kContextQuantile quantile of D divided by kContextQuantileX, so that quantile
// of the bone in view lands at x = kContextQuantileX of the presets' f(x) = 2/(1+α^x): with the
// shipped distance TFs (full within x ≈ 1.1, half at x ≈ 2.6, gone by x ≈ 4.7) the nearer bone
// in view is context and the farther fades out inside the view, on any scan and voxel size. The
// shipped presets' x (and lighting's α of Eq. 6, applied to D / unit) are in this unit.
//
// Cost: one pass over the field's voxels inside the reach's box (a subsample of at most
// kMaxScaleSamples of them), done once per field — not per frame.
#pragma once

#include <cstddef>
#include <optional>

#include "render/preset.h"
#include "render/scene.h"
#include "volume/grid.h"

namespace at::render {

constexpr double kContextQuantile = 0.5;
// x of the median bone in view: 1.9 units. Chosen so the phantom's structures keep about the unit
// their size gave them (cochlea ≈ 1, canals ≈ 0.7; bench/RESULTS.md has the table).
constexpr double kContextQuantileX = 1.9;
// The far quantile of the bone in view lands at x ≥ kFarQuantileX (f = 0.34: the shipped distance
// TFs have faded it to about a quarter). Where the bone's weighted distances are spread narrowly —
// on an abdominal CT every bone is reached through the same soft tissue, D of the 10th to the 90th
// percentile within a factor 2.3 — no bone is far at x = D / unit, so nothing fades and t adds
// nothing; there the map is stretched about the context quantile: x = (D − offset) / unit.
constexpr double kFarQuantile = 0.9;
constexpr double kFarQuantileX = 3.5;
constexpr std::size_t kMaxScaleSamples = 1u << 18;

struct FieldScale {
  double distanceUnit = 1;      // (D − distanceOffset) / distanceUnit is the presets' x (clamped at 0)
  double distanceOffset = 0;    // 0 unless the spread is narrow (kFarQuantileX)
  double farQuantileD = 0;      // the measured kFarQuantile quantile of D
  double quantileD = 0;         // the measured quantile of D over the context voxels
  std::size_t contextVoxels = 0;  // voxels the quantile was taken over (0: fell back)
  bool derived = false;         // false: too few context voxels, the size-based unit is kept
};

// The stored-value level from which the preset's data TF draws bone: the first TF x at which its
// opacity reaches half of its peak.
double denseLevel(const Preset& preset);

// The field's unit for a structure (see above). `volume` is the scan the field was computed on
// (any grid: it is sampled at the field's voxel centres); `body` (on the volume's grid) may be
// null. With fewer than 64 context voxels the size-based unit (distanceUnitFor) is returned,
// derived = false.
FieldScale fieldScale(const FloatVolume& field, const Volume& volume, const Mask* body, const StructureFrame& frame,
                      double denseFrom, double margin = 1.6, double minRadiusMm = 3.0);

}  // namespace at::render
