// Rendering a whole volume, with no structure selected (`render DATASET --out F.png`, datasets
// without labels): a data transfer function derived from the data and a frame around the grid.
#pragma once

#include "render/preset.h"
#include "render/scene.h"
#include "volume/grid.h"
#include "volume/intensity.h"

namespace at::render {

// A WDT-mode preset whose distance TF is transparent and t = 1, so that a sample shows the data TF
// alone. CT: air and fat clear, soft tissue (0 … 100 HU) faint, bone white from ~200 HU. Plain
// intensities, over their histogram window (volume/intensity.h): clear below 28 % of it (air,
// background), faint tissue around 35–42 %, rising to white dense material at its top, with context surfaces at edges of 1 % … 10 % of the
// window per voxel (CT: the preset's default 40 … 300 HU). Opacities
// are per kWholeVolumeRefMm of ray and scaled to the grid's size, so tissue stays a haze and bone
// shows on any scan. TF points are in stored values, as the ray caster samples them.
constexpr double kWholeVolumeRefMm = 0.25;
Preset wholeVolumePreset(const IntensityModel& intensity, const Geometry& grid);

// The frame of the whole grid: its centre, 0.6 × its largest side as the radius, and its corner
// voxels as the points a view is framed around.
StructureFrame volumeFrame(const Geometry& grid);

// A field that puts every sample "at the structure" (distance 0), for modes that sample one: with
// the transparent distance TF above it changes nothing. Two voxels per axis over the grid.
FloatVolume neutralField(const Geometry& grid);

}  // namespace at::render
