// CUDA side of the renderer's field upload: map the registered GL texture as a CUDA array and
// copy the device field into it (cudaMemcpy3D device → array), then unmap so GL may sample it.
#include "cuda/gl_interop.h"

#include <string>

#include <cuda_runtime.h>
#include <GL/gl.h>
#include <cuda_gl_interop.h>

#include "cuda/wdt_cuda.h"

namespace at::cuda {

namespace {
Status check(cudaError_t e, const char* call) {
  if (e == cudaSuccess) return {};
  return fail(std::string(call) + ": " + cudaGetErrorString(e));
}
}  // namespace

struct GlTextureTarget::Impl {
  cudaGraphicsResource_t resource = nullptr;
  int width = 0, height = 0, depth = 0;
  ~Impl() {
    if (resource) cudaGraphicsUnregisterResource(resource);
  }
};

GlTextureTarget::GlTextureTarget(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
GlTextureTarget::~GlTextureTarget() = default;
GlTextureTarget::GlTextureTarget(GlTextureTarget&&) noexcept = default;
GlTextureTarget& GlTextureTarget::operator=(GlTextureTarget&&) noexcept = default;

Result<GlTextureTarget> GlTextureTarget::registerTexture(unsigned glTexture3d, int width, int height, int depth) {
  auto impl = std::make_unique<Impl>();
  impl->width = width;
  impl->height = height;
  impl->depth = depth;
  if (auto s = check(cudaGraphicsGLRegisterImage(&impl->resource, GLuint(glTexture3d), GL_TEXTURE_3D,
                                                 cudaGraphicsRegisterFlagsWriteDiscard),
                     "cudaGraphicsGLRegisterImage");
      !s)
    return tl::unexpected(s.error());
  return GlTextureTarget(std::move(impl));
}

Status GlTextureTarget::copyFrom(const DeviceField& field) {
  const Dims& d = field.grid().dims;
  if (d.x != impl_->width || d.y != impl_->height || d.z != impl_->depth)
    return fail("CUDA–GL interop: field " + d.toString() + " does not match the texture " +
                std::to_string(impl_->width) + "x" + std::to_string(impl_->height) + "x" + std::to_string(impl_->depth));
  if (!field.devicePointer()) return fail("CUDA–GL interop: the device field is empty");
  if (auto s = check(cudaGraphicsMapResources(1, &impl_->resource, 0), "cudaGraphicsMapResources"); !s) return s;
  cudaArray_t array = nullptr;
  Status result = check(cudaGraphicsSubResourceGetMappedArray(&array, impl_->resource, 0, 0),
                        "cudaGraphicsSubResourceGetMappedArray");
  if (result) {
    cudaMemcpy3DParms p{};
    p.srcPtr = make_cudaPitchedPtr(const_cast<void*>(field.devicePointer()), std::size_t(d.x) * sizeof(float),
                                   std::size_t(d.x), std::size_t(d.y));
    p.dstArray = array;
    p.extent = make_cudaExtent(std::size_t(d.x), std::size_t(d.y), std::size_t(d.z));
    p.kind = cudaMemcpyDeviceToDevice;
    result = check(cudaMemcpy3D(&p), "cudaMemcpy3D");
  }
  const Status unmap = check(cudaGraphicsUnmapResources(1, &impl_->resource, 0), "cudaGraphicsUnmapResources");
  if (!result) return result;
  return unmap;
}

}  // namespace at::cuda
