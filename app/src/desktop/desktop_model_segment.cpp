// DesktopModel: the segment editor's brush on the 3-D view (desktop_model.h, brushAt).
#include "desktop_model.h"
#include "segment_controller.h"

namespace at::app {

namespace {
// The brush's centre: where the ray's accumulated opacity reaches a quarter — the first surface
// the user sees (a translucent CT shows its skin as a shell of about that), not the sample behind
// it where a hover's pick (kSeenThroughOpacity) looks through bone.
constexpr double kBrushSurfaceOpacity = 0.25;
}  // namespace

void DesktopModel::brushAt(double x, double y) {
  if (!layout_.inView(x, y) || study_->participantActive()) return;
  const render::PickResult surface = pickAt(x, y, kBrushSurfaceOpacity);
  if (!surface.hit) return;  // off the volume: nothing
  auto dab = segment_->brushAt(surface.pointMm);
  if (!dab) {
    message(dab.error().message);
    return;
  }
  // The slices follow the brush, so the painted ball shows in them (as a 3-D pick moves them).
  if (slices_.moveToPoint(surface.pointMm)) {
    const auto& v = slices_.crosshair();
    event({{"event", "crosshair"}, {"voxel", {v[0], v[1], v[2]}}});
    (void)segment_->setSlice(segment_->axis(), v[std::size_t(segment_->axis())]);
  }
}

}  // namespace at::app
