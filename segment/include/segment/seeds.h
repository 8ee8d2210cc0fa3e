// Seeds as a user marks them: labels, and strokes (polylines in mm with a radius) or single points
// in the patient frame. The seeds file of `anatomy-tutor segment` (schema below) and its
// rasterisation into seed voxels of a grid.
//
//   { "schema": 1,
//     "space": "LPS",                                   LPS (default) or RAS millimetres
//     "labels": [ {"value": 0, "name": "background"},
//                 {"value": 5, "name": "liver", "colour": [0.86, 0.55, 0.39],
//                  "range": [-50, 250], "min_diameter_mm": 3},          (threshold method only)
//                 {"value": 2, "name": "mandible", "grow_range": "bone"} ],  grow: keep only values in
//                                                   [low, high] or the data's bone range (ranged_growth.h)
//     "strokes": [ {"label": "liver", "radius_mm": 2, "points": [[x, y, z], [x, y, z], ...]},
//                  {"label": 0, "points": [[x, y, z]]} ],     a label by name or value; one point = a dot
//     "grow": {"weight": "gradient", "window": [-160, 240], "base": 0.05, "range": [300, 3000],
//              "smoothing": 1} }                                                         optional
//
// Missing fields take defaults: space LPS, radius_mm 0 (the voxels nearest to the line), colour
// from the label's palette, no range; "grow" fields default as the segment command documents.
// Unknown fields, wrong types, duplicate label values or names, and strokes naming a label that is
// not listed are errors naming the field ("seeds.json: strokes[3].label 'kidney' is not one of the
// labels (background, liver)").
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"
#include "wdt/label_growth.h"

namespace at::segment {

struct SeedLabel {
  std::uint16_t value = 0;
  std::string name;
  std::optional<std::array<float, 3>> colour;   // linear RGB 0..1
  std::optional<std::array<double, 2>> range;   // threshold method: values (HU or intensities)
  double minDiameterMm = 0;                     // threshold method: cut bridges thinner than this
  // Grow method: the label keeps only voxels whose value lies in this range ("grow_range": [lo, hi])
  // or in the dataset's data-derived bone range ("grow_range": "bone"); segment/ranged_growth.h.
  std::optional<std::array<double, 2>> growRange;
  bool growRangeBone = false;
  bool hasGrowRange() const { return growRange.has_value() || growRangeBone; }
};

struct SeedStroke {
  std::size_t label = 0;         // index into SeedSet::labels
  std::vector<Vec3> pointsMm;    // LPS (converted from RAS on load)
  double radiusMm = 0;
};

struct GrowOptions {
  std::optional<std::string> weight;            // gradient | density | uniform | ascent
  std::optional<std::array<double, 2>> window;  // values mapped to 0 … 1
  std::optional<double> base;
  std::optional<std::array<double, 2>> range;   // grow only into values in this range ("bone only")
  // Edge-preserving smoothing of the values before growth, sigma in voxels (0 … 8; 0: none); the
  // edge sigma stays the data-derived one (segment/growth_settings.h).
  std::optional<double> smoothing;
};

struct SeedSet {
  std::vector<SeedLabel> labels;
  std::vector<SeedStroke> strokes;
  GrowOptions grow;
};

// `source` names the text in error messages.
Result<SeedSet> parseSeeds(const std::string& jsonText, const std::string& source);
Result<SeedSet> loadSeeds(const std::filesystem::path& path);
// Pretty-printed, LPS, every field that is set.
std::string seedsToJson(const SeedSet& seeds);

struct RasterisedSeeds {
  std::vector<GrowthSeed> seeds;   // sorted by voxel, one label per voxel
  std::vector<std::size_t> perLabel;  // seed voxels per SeedSet label
};

// The seed voxels of the strokes on `grid`: each stroke's polyline is sampled every half of the
// smallest spacing; every voxel whose centre lies within radius_mm of a sample is seeded, and the
// voxel nearest to it in any case. Where strokes overlap the later one wins. Errors: a stroke
// point outside the grid (naming the stroke, the point, its coordinates and the grid's extent).
// Work is bounded: the dots' radius boxes together may visit at most seedVisitBudget(grid.dims)
// voxels (the volume's voxel count, at least kMinSeedVisitBudget); more is refused before any is
// painted ("seeds: the strokes' dots would visit more than …").
Result<RasterisedSeeds> rasteriseSeeds(const SeedSet& seeds, const Geometry& grid);

inline constexpr std::size_t kMinSeedVisitBudget = std::size_t(1) << 22;
std::size_t seedVisitBudget(const Dims& dims);

// Checks that at least two labels have seed voxels (grow from seeds needs something to grow
// against); the error names the label that has them.
Status requireTwoSeededLabels(const SeedSet& seeds, const RasterisedSeeds& raster);

}  // namespace at::segment
