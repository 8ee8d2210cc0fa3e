#include "ui/volume_view.h"

#include "render/gl/window_target.h"
#include "render/volume_preset.h"

namespace at::app {

VolumeView::VolumeView(MessageSink messages) : messages_(std::move(messages)) {
  const auto version = render::gl::currentContextVersion();
  if (version[0] * 10 + version[1] < 43) {
    messages_("the volume view needs OpenGL 4.3; this context is " + render::gl::currentContextDescription());
    return;
  }
  auto renderer = render::gl::VolumeRenderer::create();
  if (!renderer) {
    messages_("volume renderer: " + renderer.error().message);
    return;
  }
  renderer_ = std::move(*renderer);
}

void VolumeView::prepare(DesktopModel& model) {
  takeDataset(model);
  if (!renderer_) return;
  renderer_->setSelected(model.explore().shown().label);
  if (auto st = renderer_->warmUp(model.renderSettings(model.scheduler().planFor(kFullLevel))); !st)
    messages_("volume renderer: " + st.error().message);
}

void VolumeView::takeDataset(DesktopModel& model) {
  if (!renderer_) return;
  const Dataset& dataset = model.dataset();
  if (datasetRevision_ != model.datasetRevision()) {
    datasetRevision_ = model.datasetRevision();
    labelRevision_ = model.labelEdit().revision;
    wholeVolume_ = false;
    if (auto st = renderer_->setVolume(dataset.volume, dataset.labels, model.gradients()); !st) {
      messages_("volume renderer: " + st.error().message);
      image_ = {};  // its textures go with it
      renderer_.reset();
      return;
    }
    if (!model.explore().wholeVolume())
      if (auto reserved = renderer_->reserveDeviceField(dataset.volume.dims()); !reserved)
        // Fields computed on a GPU arrive on the volume's grid; registering their texture now keeps
        // ~0.1 s out of the first hover (an unlabelled scan's first label pays it in its first
        // field). A failure here only moves that cost (and its error) there.
        messages_("volume renderer: " + reserved.error().message);
  }
  if (labelRevision_ != model.labelEdit().revision) {  // the segment editor changed labels
    const Dims& d = dataset.volume.dims();
    const bool next = model.labelEdit().revision == labelRevision_ + 1;  // else the whole grid
    const std::array<int, 6> box = next ? model.labelEdit().box : std::array<int, 6>{0, 0, 0, d.x, d.y, d.z};
    labelRevision_ = model.labelEdit().revision;
    if (auto st = renderer_->updateLabels(dataset.labels, box); !st) messages_("volume renderer: " + st.error().message);
  }
  if (model.explore().wholeVolume() && !wholeVolume_) {  // its data TF over a field that changes nothing
    if (auto field = renderer_->setField(render::neutralField(dataset.volume.geometry)); !field)
      messages_("volume renderer: " + field.error().message);
  }
  wholeVolume_ = model.explore().wholeVolume();
}

void VolumeView::frame(DesktopModel& model, Clock::time_point now) {
  takeDataset(model);
  model.setViewAvailable(available());
  if (!renderer_) return;
  const auto plan = model.planFrame(now);
  if (!plan) return;
  const render::RenderSettings settings = model.renderSettings(*plan);
  renderer_->setSelected(model.explore().shown().label);
  const Clock::time_point start = Clock::now();
  struct NoteCosts {  // the preparation's share of this frame's render, however it ends
    render::gl::VolumeRenderer& renderer;
    FrameRecorder& recorder;
    ~NoteCosts() {
      const render::gl::PrepareCosts c = renderer.takeCosts();
      recorder.notePrepare(c.prepareMs, c.maskMs, c.tableMs, c.occupancyMs, c.firstUses);
    }
  } noteCosts{*renderer_, model.recorder()};
  if (plan->progressive) {
    auto progress = renderer_->refine(settings, plan->budgetMs);
    if (!progress) return model.renderFailed(progress.error().message);
    RefineReport report;
    report.complete = progress->complete;
    report.displayable = progress->displayable;
    report.stride = 1 << progress->level;
    report.fraction = progress->fraction;
    report.imageMs = progress->imageMs;
    const Clock::time_point end = Clock::now();
    report.callMs = msBetween(start, end);
    if (model.refined(*plan, report, report.callMs, end)) image_ = renderer_->display();
    return;
  }
  auto image = renderer_->renderToTexture(settings);
  if (!image) {
    image_ = {};
    return model.renderFailed(image.error().message);
  }
  render::gl::finishGl();  // the cost model needs the draw's time, not its submission's
  model.rendered(*plan, msBetween(start, Clock::now()));
  image_ = *image;
}

Result<bool> VolumeView::show(const wdt::FieldService::Cached& field, std::uint16_t label) {
  if (!renderer_) return true;
  // A field computed on the GPU goes into the texture there (CUDA–GL interop). A host field goes
  // up a few slices per frame (software GL needs ~0.2 s for a 256³ field); the view keeps the
  // previous field until the new one is complete.
  if (field.device) {
    if (auto st = renderer_->setFieldFromDevice(*field.device); st) {
      renderer_->setSelected(label);
      return true;
    } else {
      messages_("CUDA-GL interop failed, uploading the field from host memory: " + st.error().message);
    }
    if (!field.host) return false;  // tried again when the host copy is there
  }
  auto complete = renderer_->uploadFieldStep(field.host->distances, kFieldUploadStepMs);
  if (complete && *complete) renderer_->setSelected(label);
  return complete;
}

}  // namespace at::app
