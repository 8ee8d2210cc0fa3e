#include "render/volume_preset.h"

#include <algorithm>
#include <cmath>

namespace at::render {

namespace {

// The opacity per `refMm` of ray that adds up to `total` over `lengthMm`.
float opacityOver(double total, double lengthMm, double refMm) {
  return float(1.0 - std::pow(1.0 - total, refMm / std::max(lengthMm, refMm)));
}

}  // namespace

double wholeVolumeRefMm(const Geometry& grid) {
  return kWholeVolumeRefMm * at::fineVoxelScale(std::max({grid.spacingMm[0], grid.spacingMm[1], grid.spacingMm[2]}));
}

Preset wholeVolumePreset(const IntensityModel& intensity, const Geometry& grid) {
  Preset p;
  p.name = "Whole volume (from the data)";
  p.id = std::string("whole_volume");
  p.mode = RenderMode::Wdt;
  p.t = 1.0f;
  const double refMm = wholeVolumeRefMm(grid);
  p.distanceTf = {{0, {1, 1, 1, 0}}, {1, {1, 1, 1, 0}}};
  const Rgba clear{0, 0, 0, 0};
  if (intensity.hounsfield()) {
    // CT is drawn at its edges (the context surfaces, interior 0: the preset's default): skin,
    // organ walls and bone surfaces as shells of about one voxel, so opacities are per voxel and a
    // 3 mm abdomen looks as a 0.5 mm head does. Soft tissue (fat to muscle, −100 … 100 HU) 15 %
    // per voxel of edge: the body's outline and organs show and the skeleton shows through them;
    // bone white from 160 HU (at 3 mm, vertebrae and ribs average 150–250 HU) to opaque at 350 HU.
    // (An opacity spread over the whole volume instead left a 3 mm abdomen nearly black.)
    const double voxel = std::min({grid.spacingMm[0], grid.spacingMm[1], grid.spacingMm[2]});
    const float tissue = opacityOver(0.15, voxel, refMm), boneLow = opacityOver(0.75, voxel, refMm),
                bone = opacityOver(0.99, voxel, refMm);
    p.surfaceGradientHu = {30, 200};
    const Rgba flesh{0.98f, 0.74f, 0.64f, tissue};
    p.dataTf = {{-1000, clear}, {-250, clear}, {-100, flesh}, {100, flesh}, {160, {0.97f, 0.93f, 0.86f, boneLow}},
                {350, {1, 1, 1, bone}}};
    return p;
  }
  const Vec3 extent = grid.extentMm();
  const double across = std::max({extent[0], extent[1], extent[2]});
  // Soft tissue adds up to 25 % opacity across the whole volume; dense material to 90 % within
  // 4 % of it (a bone's thickness), so bone shows through tissue whatever the volume's size.
  const float tissue = opacityOver(0.25, across, refMm), dense = opacityOver(0.9, 0.04 * across, refMm);
  const Rgba flesh{0.85f, 0.62f, 0.52f, tissue};
  const double lo = intensity.window[0], width = intensity.window[1] - intensity.window[0];
  const auto at = [&](double f) { return lo + f * width; };
  p.huWindow = intensity.window;
  // Context surfaces by edge strength: the CT defaults (40 … 300 HU per voxel, about 1 % … 10 % of
  // the WDT's 3000 HU window) as the same fractions of this window, so a µCT's 0 … 255 edges show.
  p.surfaceGradientHu = {float(0.013 * width), float(0.1 * width)};
  p.dataTf = {{at(0.0), clear}, {at(0.28), clear}, {at(0.35), flesh}, {at(0.42), flesh},
              {at(0.60), {0.95f, 0.9f, 0.82f, 0.5f * dense}}, {at(1.0), {1, 1, 1, dense}}};
  return p;
}

StructureFrame volumeFrame(const Geometry& grid) {
  StructureFrame f;
  f.centroidMm = grid.centreMm();
  f.anchorMm = f.centroidMm;
  const Vec3 e = grid.extentMm();
  f.radiusMm = 0.6 * std::max({e[0], e[1], e[2]});
  f.voxelCount = grid.dims.count();
  f.volumeMm3 = e[0] * e[1] * e[2];
  f.voxelMm = std::max({grid.spacingMm[0], grid.spacingMm[1], grid.spacingMm[2]});
  // The grid's eight corner voxels: framing (render/scene.h) fits them from any side.
  const int last[3] = {grid.dims.x - 1, grid.dims.y - 1, grid.dims.z - 1};
  for (int corner = 0; corner < 8; ++corner)
    f.pointsMm.push_back(grid.indexToPatient(
        {double((corner & 1) ? last[0] : 0), double((corner & 2) ? last[1] : 0), double((corner & 4) ? last[2] : 0)}));
  return f;
}

FloatVolume neutralField(const Geometry& grid) {
  Geometry g = grid;
  g.dims = {2, 2, 2};
  for (int a = 0; a < 3; ++a) {
    const int n[3] = {grid.dims.x, grid.dims.y, grid.dims.z};
    g.spacingMm[a] = grid.spacingMm[a] * std::max(1, n[a] - 1);
  }
  return FloatVolume(g, 0.0f);
}

}  // namespace at::render
