// Rendering a whole volume, with no structure selected (`render DATASET --out F.png`, datasets
// without labels): a data transfer function derived from the data and a frame around the grid.
#pragma once

#include "render/preset.h"
#include "render/scene.h"
#include "volume/grid.h"
#include "volume/intensity.h"

namespace at::render {

// A WDT-mode preset whose distance TF is transparent and t = 1, so that a sample shows the data TF
// alone. CT: drawn at its edges (context surfaces from 30 … 200 HU per voxel): air and lung clear,
// soft tissue (−100 … 100 HU) a translucent flesh shell of 15 % per voxel, bone white from 160 HU,
// opaque from 350 HU — opacities per voxel of the grid, so the look does not depend on its size.
// Plain intensities, over their histogram window (volume/intensity.h): clear below 28 % of it
// (air, background), faint tissue around 35–42 %, rising to white dense material at its top, with
// context surfaces at edges of 1 % … 10 % of the window per voxel, opacities scaled to the grid's
// size so tissue stays a haze. Opacities are given per wholeVolumeRefMm(grid) of ray (the
// renderer's RenderSettings::opacityRefMm); TF points are in stored values, as the ray caster
// samples them.
Preset wholeVolumePreset(const IntensityModel& intensity, const Geometry& grid);
// The length of ray the whole-volume preset's opacities are per: kWholeVolumeRefMm, kept voxel for
// voxel on a µCT finer than 0.1 mm (times fineVoxelScale of the largest spacing, volume/geometry.h).
constexpr double kWholeVolumeRefMm = 0.25;
double wholeVolumeRefMm(const Geometry& grid);

// The frame of the whole grid: its centre, 0.6 × its largest side as the radius, and its corner
// voxels as the points a view is framed around.
StructureFrame volumeFrame(const Geometry& grid);

// A field that puts every sample "at the structure" (distance 0), for modes that sample one: with
// the transparent distance TF above it changes nothing. Two voxels per axis over the grid.
FloatVolume neutralField(const Geometry& grid);

}  // namespace at::render
