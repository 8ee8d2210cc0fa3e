// The texture target of VolumeRenderer (volume_renderer.h: renderToTexture): the image stays in
// the texture the ray caster drew it into, for a UI in the same context to show; nothing is read
// back to host memory.
#include "render/gl/volume_renderer.h"
#include "renderer_state.h"

namespace at::render::gl {

Result<DisplayImage> VolumeRenderer::renderToTexture(const RenderSettings& s) {
  if (auto st = draw(s, true); !st) return tl::unexpected(st.error());
  DisplayImage out;
  out.handle = std::uintptr_t(state_->colour.id());
  handOut(*state_, state_->colour.id());
  out.texelsWide = s.width;
  out.texelsHigh = s.height;
  out.uv0 = {0, 0};
  out.uv1 = {1, 1};
  return out;
}

}  // namespace at::render::gl
