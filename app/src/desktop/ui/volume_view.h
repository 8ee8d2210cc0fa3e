// The volume view: render/gl's ray caster in the window's GL context. It takes the dataset's
// volume when it changes, takes the field the model's FieldView wants (from CUDA device memory
// through interop, else from host memory a few slices per frame) and renders what the scheduler
// plans into the renderer's own texture, which the window draws behind the panels as it is (no
// read-back to host memory and upload again).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "desktop_model.h"
#include "render/gl/volume_renderer.h"

namespace at::app {

inline constexpr double kFieldUploadStepMs = 20;  // per frame, for a field uploaded from host memory

class VolumeView final : public FieldTarget {
 public:
  using MessageSink = std::function<void(const std::string&)>;
  // Needs the window's context current. When it is older than OpenGL 4.3 or the ray caster does
  // not build, the view is unavailable and `messages` says why.
  explicit VolumeView(MessageSink messages);
  bool available() const { return renderer_.has_value(); }

  // Before the first frame: uploads the model's volume and compiles the ray-caster variants its
  // view draws (on a software rasteriser each takes 0.1–1 s at its first use), so that no frame
  // pays for either.
  void prepare(DesktopModel& model);
  // Each frame: uploads the model's volume when another dataset is shown (its labels after an
  // edit in the segment editor), then renders the plan.
  void frame(DesktopModel& model, Clock::time_point now);
  // The image to draw (handle 0 before the first one).
  const render::gl::DisplayImage& image() const { return image_; }

  Result<bool> show(const wdt::FieldService::Cached& field, std::uint16_t label) override;

 private:
  // Uploads the volume when another dataset is shown, the edited labels' box after an edit, and
  // the neutral field when the view turns to the whole volume.
  void takeDataset(DesktopModel& model);
  MessageSink messages_;
  std::optional<render::gl::VolumeRenderer> renderer_;
  render::gl::DisplayImage image_;
  std::uint64_t datasetRevision_ = 0;
  std::uint64_t labelRevision_ = 0;  // the model's labelEdit() uploaded
  bool wholeVolume_ = false;         // the neutral field is set (whole-volume mode)
};

}  // namespace at::app
