// The ray caster: uploads, the per-frame preparation (mask, table, occupancy, uniforms) and whole
// frames. Progressive refinement is in progressive.cpp, the GLSL in ray_shaders.cpp.
#include "render/gl/volume_renderer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ray_shaders.h"
#include "renderer_state.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/wdt_cuda.h"
#endif

namespace at::render::gl {

std::string RayVariant::defines() const {
  return "#define RAY_MODE " + std::to_string(mode) + "\n#define RAY_SHADING " + (shading ? "1" : "0") +
         "\n#define RAY_CLIP " + (clip ? "1" : "0") + "\n#define RAY_STRUCTURE " + (structure ? "1" : "0") + "\n";
}

std::string glErrorName(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    default: {
      char buf[16];
      std::snprintf(buf, sizeof buf, "0x%04x", unsigned(e));
      return buf;
    }
  }
}

Status pendingGlError(const char* what) {
  const GLenum e = glGetError();
  if (e == GL_NO_ERROR) return {};
  return fail("GL: error " + glErrorName(e) + " raised before " + what + " (by other GL code in the context)");
}

Status glStatus(const char* what) {
  const GLenum e = glGetError();
  if (e == GL_NO_ERROR) return {};
  if (e == GL_OUT_OF_MEMORY) return fail(std::string("GL: out of GPU memory during ") + what);
  return fail("GL: error " + glErrorName(e) + " during " + what);
}

void allocateImage(VolumeRenderer::State& st, Texture& texture, int width, int height) {
  if (texture && texture.id() == st.handedOut) st.retired = std::move(texture);
  texture = Texture::make();
  glBindTexture(GL_TEXTURE_2D, texture.id());
  glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, width, height);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

void handOut(VolumeRenderer::State& st, GLuint texture) {
  st.handedOut = texture;
  if (st.retired.id() != texture) st.retired = Texture();
}

namespace {

std::string shaderLog(GLuint shader) {
  GLint len = 0;
  glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &len);
  std::string log(std::size_t(std::max(len, 1)), '\0');
  glGetShaderInfoLog(shader, len, nullptr, log.data());
  return log;
}

template <class S>
Result<S> compile(const char* source, const char* what) {
  S s = S::make();
  glShaderSource(s.id(), 1, &source, nullptr);
  glCompileShader(s.id());
  GLint ok = 0;
  glGetShaderiv(s.id(), GL_COMPILE_STATUS, &ok);
  if (!ok) return fail(std::string("GL: ") + what + " shader does not compile: " + shaderLog(s.id()));
  return s;
}

Result<Program> link(std::initializer_list<GLuint> shaders, const char* what) {
  Program p = Program::make();
  for (GLuint sh : shaders) glAttachShader(p.id(), sh);
  glLinkProgram(p.id());
  GLint ok = 0;
  glGetProgramiv(p.id(), GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(p.id(), GL_INFO_LOG_LENGTH, &len);
    std::string log(std::size_t(std::max(len, 1)), '\0');
    glGetProgramInfoLog(p.id(), len, nullptr, log.data());
    return fail(std::string("GL: the ") + what + " does not link: " + log);
  }
  return p;
}

// Matrix taking patient mm (LPS) to normalised texture coordinates of `g` (voxel centres at
// (i + 0.5) / dims).
Mat4 patientToTexture(const Geometry& g) {
  Mat4 m;  // index = D⁻¹ S⁻¹ (p − o);  tex = (index + 0.5) / dims
  const Mat3 dinv = g.direction.inverse();
  const double dims[3] = {double(g.dims.x), double(g.dims.y), double(g.dims.z)};
  for (int r = 0; r < 3; ++r) {
    const double s = 1.0 / (g.spacingMm[std::size_t(r)] * dims[r]);
    double off = 0;
    for (int c = 0; c < 3; ++c) {
      m(r, c) = dinv.m[std::size_t(r)][std::size_t(c)] * s;
      off += dinv.m[std::size_t(r)][std::size_t(c)] * g.originMm[std::size_t(c)];
    }
    m(r, 3) = -off * s + 0.5 / dims[r];
  }
  return m;
}

// A field uploaded from the host is held as half floats: half the memory and texture traffic of
// float32, and f(D) needs no finer distances (relative precision 1/1024). Distances are clamped to
// the largest half, which the shader's normalisation treats as far, like +infinity (unreachable).
// (A field from CUDA stays float32: the interop copy writes float32.)
constexpr GLenum kFieldFormat = GL_R16F;
void copyFinite(const float* src, std::size_t count, float* dst) {
  for (std::size_t i = 0; i < count; ++i) dst[i] = std::isfinite(src[i]) ? std::min(src[i], 65504.0f) : 65504.0f;
}

void setTextureParams(GLenum filter) {
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GLint(filter));
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GLint(filter));
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

// A field texture of `d` texels (contents undefined). Mutable storage, as setField's: the
// texture may become the field texture, which setField and setFieldFromDevice re-specify.
void allocateField(Texture& texture, const Dims& d) {
  texture = Texture::make();
  glBindTexture(GL_TEXTURE_3D, texture.id());
  setTextureParams(GL_LINEAR);
  glTexImage3D(GL_TEXTURE_3D, 0, kFieldFormat, d.x, d.y, d.z, 0, GL_RED, GL_FLOAT, nullptr);
}

// The pending texture goes to the spares (none pending afterwards).
void keepSpareField(VolumeRenderer::State& st) {
  if (st.pendingField) {
    st.spareFields.emplace_back(st.pendingDims, std::move(st.pendingField));
    if (st.spareFields.size() > VolumeRenderer::State::kSpareFields) st.spareFields.erase(st.spareFields.begin());
  }
  st.pendingField = Texture();
  st.pendingDims = Dims{};
}

// Makes a spare of dims `d` the pending texture; false when there is none.
bool takeSpareField(VolumeRenderer::State& st, const Dims& d) {
  const auto found = std::find_if(st.spareFields.begin(), st.spareFields.end(), [&](const auto& s) { return s.first == d; });
  if (found == st.spareFields.end()) return false;
  st.pendingField = std::move(found->second);
  st.pendingDims = d;
  st.spareFields.erase(found);
  return true;
}

// The ray caster program of one variant, compiled and linked on first use, then kept.
Result<GLuint> rayCasterProgram(VolumeRenderer::State& st, RayCaster kind, RayVariant variant) {
  Program& slot = kind == RayCaster::Compute ? st.computeRayCasters[std::size_t(variant.index())]
                                             : st.fragmentRayCasters[std::size_t(variant.index())];
  if (slot) return slot.id();
  const std::string source = "#version 430 core\n" + variant.defines() + shaders::kRayCaster;
  if (kind == RayCaster::Compute) {
    auto main = compile<ComputeShader>(shaders::kComputeMain, "compute");
    if (!main) return tl::unexpected(main.error());
    auto ray = compile<ComputeShader>(source.c_str(), "compute ray caster");
    if (!ray) return tl::unexpected(ray.error());
    auto linked = link({main->id(), ray->id()}, "compute ray caster");
    if (!linked) return tl::unexpected(linked.error());
    slot = std::move(*linked);
  } else {
    auto vs = compile<VertexShader>(shaders::kFullScreenVertex, "vertex");
    if (!vs) return tl::unexpected(vs.error());
    auto main = compile<FragmentShader>(shaders::kFragmentMain, "fragment");
    if (!main) return tl::unexpected(main.error());
    auto ray = compile<FragmentShader>(source.c_str(), "fragment ray caster");
    if (!ray) return tl::unexpected(ray.error());
    auto linked = link({vs->id(), main->id(), ray->id()}, "fragment ray caster");
    if (!linked) return tl::unexpected(linked.error());
    slot = std::move(*linked);
  }
  return slot.id();
}

// The selected label's box in voxels (min inclusive, max exclusive), a voxel wider than the
// blocks holding it (the smoothed mask reaches one voxel out); empty when no block holds it.
std::array<int, 6> labelBox(const BlockSummary& b, const Dims& dims, std::uint16_t label) {
  int lo[3] = {b.blocks.x, b.blocks.y, b.blocks.z}, hi[3] = {-1, -1, -1};
  const auto found = label != 0 ? b.blocksOfLabel.find(label) : b.blocksOfLabel.end();
  if (found != b.blocksOfLabel.end())
    for (std::uint32_t block : found->second) {
      const std::uint32_t nx = std::uint32_t(b.blocks.x), ny = std::uint32_t(b.blocks.y);
      const int c[3] = {int(block % nx), int(block / nx % ny), int(block / (nx * ny))};
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(lo[a], c[a]);
        hi[a] = std::max(hi[a], c[a]);
      }
    }
  if (hi[0] < 0) return {0, 0, 0, 0, 0, 0};
  const int d[3] = {dims.x, dims.y, dims.z};
  std::array<int, 6> box{};
  for (int a = 0; a < 3; ++a) {
    box[std::size_t(a)] = std::max(0, lo[a] * kBlockVoxels - 1);
    box[std::size_t(a + 3)] = std::min(d[a], (hi[a] + 1) * kBlockVoxels + 1);
  }
  return box;
}

}  // namespace

Result<Program> linkCompute(const char* source, const char* what) {
  auto cs = compile<ComputeShader>(source, what);
  if (!cs) return tl::unexpected(cs.error());
  return link({cs->id()}, what);
}

VolumeRenderer::VolumeRenderer(std::unique_ptr<State> s) : state_(std::move(s)) {}
VolumeRenderer::~VolumeRenderer() = default;
VolumeRenderer::VolumeRenderer(VolumeRenderer&&) noexcept = default;
VolumeRenderer& VolumeRenderer::operator=(VolumeRenderer&&) noexcept = default;

Result<VolumeRenderer> VolumeRenderer::create() {
  auto s = std::make_unique<State>();
  // Compile the default mode's ray casters now, so that a driver that rejects the shader fails
  // here, with its message, rather than at the first frame.
  for (RayCaster kind : {RayCaster::Compute, RayCaster::Fragment})
    if (auto p = rayCasterProgram(*s, kind, RayVariant{}); !p) return tl::unexpected(p.error());
  auto mask = linkCompute(shaders::kMaskShader, "mask");
  if (!mask) return tl::unexpected(mask.error());
  s->maskProgram = std::move(*mask);
  s->vao = VertexArray::make();
  s->labels = Texture::make();
  s->field = Texture::make();
  {
    // A far field of one texel in the format host fields take, so that the texture is complete
    // and alike before and after the first field (a software rasteriser's compiled shaders depend
    // on the formats of the textures bound).
    const float far = 65504.0f;
    glBindTexture(GL_TEXTURE_3D, s->field.id());
    setTextureParams(GL_LINEAR);
    glTexImage3D(GL_TEXTURE_3D, 0, kFieldFormat, 1, 1, 1, 0, GL_RED, GL_FLOAT, &far);
    s->fieldDims = {1, 1, 1};
  }
  s->table = Texture::make();
  s->fbo = Framebuffer::make();
  s->timer = Query::make();
  if (auto st = glStatus("creating the ray caster"); !st) return tl::unexpected(st.error());
  return VolumeRenderer(std::move(s));
}

Status VolumeRenderer::setVolume(const Volume& volume, const LabelMap& labels) {
  if (volume.empty()) return fail("render: the volume is empty");
  return setVolume(volume, labels, computeGradientVolume(volume));
}

Status VolumeRenderer::setVolume(const Volume& volume, const LabelMap& labels, const GradientVolume& gradients) {
  if (volume.empty()) return fail("render: the volume is empty");
  if (!labels.empty() && !(labels.dims() == volume.dims()))
    return fail("render: labels " + labels.dims().toString() + " are not on the volume's grid " +
                volume.dims().toString());
  if (gradients.texels.size() != volume.voxels.size())
    return fail("render: the gradient volume is not on the volume's grid");
  State& st = *state_;
  const Dims& d = volume.dims();
  // A field upload in progress belongs to the previous volume; its texture is kept as a spare,
  // and one on this volume's grid is made now (software GL: tens of ms at 256³, which the first
  // full-resolution field would otherwise spend in a frame).
  keepSpareField(st);
  st.pendingSource = nullptr;
  st.pendingGrid = Geometry{};
  if (!takeSpareField(st, d)) {
    allocateField(st.pendingField, d);
    st.pendingDims = d;
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_3D, st.labels.id());
  setTextureParams(GL_NEAREST);
  if (labels.empty()) {
    std::vector<std::uint16_t> zeros(volume.voxels.size(), 0);
    glTexImage3D(GL_TEXTURE_3D, 0, GL_R16UI, d.x, d.y, d.z, 0, GL_RED_INTEGER, GL_UNSIGNED_SHORT, zeros.data());
  } else {
    glTexImage3D(GL_TEXTURE_3D, 0, GL_R16UI, d.x, d.y, d.z, 0, GL_RED_INTEGER, GL_UNSIGNED_SHORT, labels.voxels.data());
  }
  // The mask texture needs immutable storage to be written as an image; it starts all zero.
  st.mask = Texture::make();
  glBindTexture(GL_TEXTURE_3D, st.mask.id());
  glTexStorage3D(GL_TEXTURE_3D, 1, GL_R8, d.x, d.y, d.z);
  setTextureParams(GL_LINEAR);
  {
    const std::vector<std::uint8_t> zeros(volume.voxels.size(), 0);
    glTexSubImage3D(GL_TEXTURE_3D, 0, 0, 0, 0, d.x, d.y, d.z, GL_RED, GL_UNSIGNED_BYTE, zeros.data());
  }
  st.maskLabel = -1;
  st.maskBox = {0, 0, 0, 0, 0, 0};
  st.volume = Texture::make();
  glBindTexture(GL_TEXTURE_3D, st.volume.id());
  glTexStorage3D(GL_TEXTURE_3D, 1, GL_RGBA16_SNORM, d.x, d.y, d.z);
  setTextureParams(GL_LINEAR);
  glTexSubImage3D(GL_TEXTURE_3D, 0, 0, 0, 0, d.x, d.y, d.z, GL_RGBA, GL_SHORT, gradients.texels.data());
  st.blocks = summariseBlocks(volume, labels, gradients);
  const Dims& nb = st.blocks.blocks;
  st.occupancy = Texture::make();
  glBindTexture(GL_TEXTURE_3D, st.occupancy.id());
  glTexStorage3D(GL_TEXTURE_3D, 1, GL_R8UI, nb.x, nb.y, nb.z);
  setTextureParams(GL_NEAREST);
  st.occupancyKey.reset();
  st.contextKey.reset();
  st.fieldFreeKey.reset();
  st.occupancyJob.reset();
  st.volumeGrid = volume.geometry;
  st.hasVolume = true;
  st.hasField = false;
  st.fieldOnCpu = false;
  ++st.sceneGeneration;
  ++st.fieldGeneration;
  return glStatus("uploading the volume");
}

Status VolumeRenderer::updateLabels(const LabelMap& labels, const std::array<int, 6>& box) {
  State& st = *state_;
  if (!st.hasVolume) return fail("render: no volume uploaded");
  const Dims& d = st.volumeGrid.dims;
  if (!(labels.dims() == d))
    return fail("render: labels " + labels.dims().toString() + " are not on the volume's grid " + d.toString());
  const int x0 = std::max(0, box[0]), y0 = std::max(0, box[1]), z0 = std::max(0, box[2]);
  const int x1 = std::min(d.x, box[3]), y1 = std::min(d.y, box[4]), z1 = std::min(d.z, box[5]);
  if (x1 <= x0 || y1 <= y0 || z1 <= z0) return {};
  // The box's rows, packed (a sub-image upload reads a contiguous block).
  const std::size_t w = std::size_t(x1 - x0);
  std::vector<std::uint16_t> packed(w * std::size_t(y1 - y0) * std::size_t(z1 - z0));
  auto out = packed.begin();
  for (int k = z0; k < z1; ++k)
    for (int j = y0; j < y1; ++j) {
      const auto row = labels.voxels.begin() + std::ptrdiff_t(d.index(x0, j, k));
      out = std::copy(row, row + std::ptrdiff_t(w), out);
    }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_3D, st.labels.id());
  glTexSubImage3D(GL_TEXTURE_3D, 0, x0, y0, z0, x1 - x0, y1 - y0, z1 - z0, GL_RED_INTEGER, GL_UNSIGNED_SHORT,
                  packed.data());
  updateBlockLabels(st.blocks, labels, {x0, y0, z0, x1, y1, z1});
  // The mask clears its old box and fills the new one at the next draw; the empty-space grid adds
  // the structure's blocks again to the kept context grid.
  st.maskLabel = -1;
  st.occupancyKey.reset();
  ++st.sceneGeneration;
  return glStatus("uploading edited labels");
}

bool VolumeRenderer::hasCudaInterop() {
#if defined(AT_HAVE_CUDA)
  return true;
#else
  return false;
#endif
}

#if defined(AT_HAVE_CUDA)
namespace {
// Gives the field texture storage of `dims` registered with CUDA, unless it has it already. The
// registration costs ~70-170 ms once per storage (driver work), so it is kept until the storage
// changes (setField, uploads).
Status ensureInteropStorage(VolumeRenderer::State& st, const Dims& dims) {
  if (st.interop && st.interopDims == dims) return {};
  st.interop.reset();
  glBindTexture(GL_TEXTURE_3D, st.field.id());
  setTextureParams(GL_LINEAR);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, dims.x, dims.y, dims.z, 0, GL_RED, GL_FLOAT, nullptr);
  st.fieldDims = dims;
  if (auto s = glStatus("allocating the distance field"); !s) return s;
  auto target = cuda::GlTextureTarget::registerTexture(st.field.id(), dims.x, dims.y, dims.z);
  if (!target) return tl::unexpected(target.error());
  st.interop.emplace(std::move(*target));
  st.interopDims = dims;
  return {};
}
}  // namespace
#endif

Result<bool> VolumeRenderer::reserveDeviceField(const Dims& dims) {
#if defined(AT_HAVE_CUDA)
  if (!cuda::queryDevice().available) return false;
  State& st = *state_;
  if (st.hasField) return false;  // never replaces a field being shown
  if (auto s = ensureInteropStorage(st, dims); !s) return tl::unexpected(s.error());
  return true;
#else
  (void)dims;
  return false;
#endif
}

Status VolumeRenderer::setFieldFromDevice(const cuda::DeviceField& field) {
#if defined(AT_HAVE_CUDA)
  State& st = *state_;
  const Geometry& grid = field.grid();
  if (auto s = ensureInteropStorage(st, grid.dims); !s) return s;
  if (auto s = st.interop->copyFrom(field); !s) return s;
  st.fieldGrid = grid;
  st.hasField = true;
  st.fieldOnCpu = false;
  ++st.sceneGeneration;
  ++st.fieldGeneration;
  return {};
#else
  (void)field;
  return fail(ErrorKind::Unavailable, "render: this build has no CUDA, so a device field cannot be shown");
#endif
}

Status VolumeRenderer::setField(const FloatVolume& field) {
  if (field.empty()) return fail("render: the distance field is empty");
  if (auto pending = pendingGlError("the field upload"); !pending) return pending;
  State& st = *state_;
  std::vector<float> finite(field.voxels.size());
  copyFinite(field.voxels.data(), finite.size(), finite.data());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_3D, st.field.id());
  setTextureParams(GL_LINEAR);
  const Dims& d = field.dims();
  glTexImage3D(GL_TEXTURE_3D, 0, kFieldFormat, d.x, d.y, d.z, 0, GL_RED, GL_FLOAT, finite.data());
  st.fieldDims = d;
#if defined(AT_HAVE_CUDA)
  st.interop.reset();  // the storage changed: a registration would be stale
#endif
  st.fieldMinima.addAll(field);
  st.fieldGrid = field.geometry;
  st.hasField = true;
  st.fieldOnCpu = true;
  ++st.sceneGeneration;
  ++st.fieldGeneration;
  return glStatus("uploading the distance field");
}

Result<bool> VolumeRenderer::uploadFieldStep(const FloatVolume& field, double budgetMs) {
  if (field.empty()) return fail("render: the distance field is empty");
  if (auto pending = pendingGlError("the field upload"); !pending) return tl::unexpected(pending.error());
  State& st = *state_;
  const Dims& d = field.dims();
  const Geometry& g = field.geometry;
  const bool sameGrid = st.pendingGrid.dims == g.dims && st.pendingGrid.spacingMm == g.spacingMm &&
                        st.pendingGrid.originMm == g.originMm;
  if (st.pendingSource != field.voxels.data() || !sameGrid) {
    // A new field. The spare texture (the field texture before the last swap) is reused when it
    // has these dims; allocating one (software GL: tens of ms at 256³) is a call's whole work.
    st.pendingSource = field.voxels.data();
    st.pendingGrid = g;
    st.pendingNextSlice = 0;
    st.pendingMinima.reset(g);
    if (!st.pendingField || !(st.pendingDims == d)) {
      keepSpareField(st);
      if (!takeSpareField(st, d)) {
        allocateField(st.pendingField, d);
        st.pendingDims = d;
        if (auto e = glStatus("allocating the distance field"); !e) return tl::unexpected(e.error());
        return false;
      }
    }
  }
  const auto start = std::chrono::steady_clock::now();
  const std::size_t slice = std::size_t(d.x) * std::size_t(d.y);
  std::vector<float> finite(slice);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_3D, st.pendingField.id());
  // At least one slice a call, never past the last: a call after a failed one may find every
  // slice sent (the loop once ran a slice past the field's end there: a heap overflow).
  while (st.pendingNextSlice < d.z) {
    const float* src = field.voxels.data() + slice * std::size_t(st.pendingNextSlice);
    copyFinite(src, slice, finite.data());
    st.pendingMinima.addSlice(src, st.pendingNextSlice);
    glTexSubImage3D(GL_TEXTURE_3D, 0, 0, 0, st.pendingNextSlice, d.x, d.y, 1, GL_RED, GL_FLOAT, finite.data());
    ++st.pendingNextSlice;
    if (std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() >= budgetMs) break;
  }
  if (auto e = glStatus("uploading the distance field"); !e) {
    st.pendingSource = nullptr;  // the next call starts this field again, on a fresh texture
    st.pendingGrid = Geometry{};
    st.pendingField = Texture();
    st.pendingDims = Dims{};
    return tl::unexpected(e.error());
  }
  if (st.pendingNextSlice < d.z) return false;
  // The filled texture becomes the field; the previous field texture is the spare for the next.
  std::swap(st.field, st.pendingField);
  std::swap(st.fieldDims, st.pendingDims);
  std::swap(st.fieldMinima, st.pendingMinima);
  st.pendingSource = nullptr;
  st.pendingGrid = Geometry{};
#if defined(AT_HAVE_CUDA)
  st.interop.reset();  // the storage changed: a registration would be stale
#endif
  st.fieldGrid = field.geometry;
  st.hasField = true;
  st.fieldOnCpu = true;
  ++st.sceneGeneration;
  ++st.fieldGeneration;
  return true;
}

void VolumeRenderer::clearField() {
  if (!state_->hasField) return;
  state_->hasField = false;
  ++state_->sceneGeneration;
  ++state_->fieldGeneration;
}

void VolumeRenderer::setSelected(std::uint16_t label) {
  if (state_->selected == label) return;
  state_->selected = label;
  ++state_->sceneGeneration;
}

void VolumeRenderer::setRayCaster(RayCaster r) { state_->rayCaster = r; }

Status VolumeRenderer::warmUp(const RenderSettings& settings) {
  RenderSettings s = settings;
  s.width = s.height = 8;
  // The shader's four modes (WDT stands for the table modes but outline), with and without a
  // structure (selecting and hovering switch between the two) and shading (coarse and full levels).
  for (RenderMode mode : {RenderMode::Wdt, RenderMode::Bare, RenderMode::Lighting, RenderMode::Outline})
    for (int structure : {0, 1})
      for (bool shading : {false, true}) {
        s.preset.mode = mode;
        s.shading = s.jitter = shading;
        state_->warmStructure = structure;
        const Status drawn = draw(s, true);
        state_->warmStructure = -1;
        if (!drawn) return drawn;
      }
  takeCosts();  // what a frame reports is its own
  glFinish();
  return glStatus("warming the ray caster up");
}

PrepareCosts VolumeRenderer::takeCosts() { return std::exchange(state_->costs, PrepareCosts{}); }

// Brings the mask, the table and the occupancy grid up to date for `s` and binds the ray caster
// program with its uniforms and textures (the compute image binding is the caller's).
Status VolumeRenderer::prepare(const RenderSettings& s, bool interactive) {
  if (auto pending = pendingGlError("this frame's render"); !pending) return pending;
  const auto start = std::chrono::steady_clock::now();
  const Status prepared = prepareState(s, interactive);
  state_->costs.prepareMs += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!prepared) forgetPrepared();
  return prepared;
}

void VolumeRenderer::forgetPrepared() {
  // A failed call may have left any of these half-made (a texture upload that raised the error, a
  // key recorded for it): the next call builds all of them again instead of trusting them.
  State& st = *state_;
  st.maskLabel = -1;
  st.tablePreset.reset();
  st.occupancyKey.reset();
  st.contextKey.reset();
  st.fieldFreeKey.reset();
  st.occupancyJob.reset();
  st.progressive.active = false;
}

Status VolumeRenderer::prepareState(const RenderSettings& s, bool interactive) {
  if (!state_->hasVolume) return fail("render: no volume uploaded");
  if (s.width <= 0 || s.height <= 0 || s.width > 16384 || s.height > 16384)
    return fail("render: image size " + std::to_string(s.width) + "x" + std::to_string(s.height) + " is out of range");
  if (!(s.distanceUnit > 0) || !std::isfinite(s.distanceUnit))
    return fail("render: the distance unit must be a positive number");
  State& st = *state_;
  const Dims& vd = st.volumeGrid.dims;
  using Clock = std::chrono::steady_clock;
  const auto msSince = [](Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); };
  if (st.maskLabel != int(st.selected)) {
    const Clock::time_point maskStart = Clock::now();
    glUseProgram(st.maskProgram.id());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_3D, st.labels.id());
    glUniform1i(glGetUniformLocation(st.maskProgram.id(), "uLabels"), 0);
    glBindImageTexture(1, st.mask.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R8);
    glUniform1ui(glGetUniformLocation(st.maskProgram.id(), "uSelected"), st.selected);
    glUniform3i(glGetUniformLocation(st.maskProgram.id(), "uDims"), vd.x, vd.y, vd.z);
    const auto run = [&](const std::array<int, 6>& box, int clear) {
      const int ex = box[3] - box[0], ey = box[4] - box[1], ez = box[5] - box[2];
      if (ex <= 0 || ey <= 0 || ez <= 0) return;
      glUniform3i(glGetUniformLocation(st.maskProgram.id(), "uBoxMin"), box[0], box[1], box[2]);
      glUniform3i(glGetUniformLocation(st.maskProgram.id(), "uBoxMax"), box[3], box[4], box[5]);
      glUniform1i(glGetUniformLocation(st.maskProgram.id(), "uClear"), clear);
      glDispatchCompute(GLuint((ex + 7) / 8), GLuint((ey + 7) / 8), GLuint((ez + 3) / 4));
      glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT);
    };
    run(st.maskBox, 1);
    st.maskBox = labelBox(st.blocks, vd, st.selected);
    run(st.maskBox, 0);
    st.maskLabel = int(st.selected);
    if (auto e = glStatus("building the structure mask"); !e) return e;
    st.costs.maskMs += msSince(maskStart);
  }
  // The 2-D table of the mode, its opacities corrected to the step.
  const double stepMm = effectiveStepMm(st.volumeGrid, s);
  const double refMm = effectiveOpacityRefMm(st.volumeGrid, s);
  if (!st.tablePreset || !sameShadingTable(*st.tablePreset, s.preset) || st.tableStepMm != stepMm ||
      st.tableRefMm != refMm) {
    const Clock::time_point tableStart = Clock::now();
    TransferFunction2D table = shadingTable(s.preset);
    for (Rgba& v : table.rgba) v[3] = v[3] > 0.0f ? correctedOpacity(v[3], stepMm, refMm) : 0.0f;
    // What the context can draw (opacity > 0) does not depend on the step: the occupancy grid
    // is kept when only the step changes (the desktop alternates coarse and full levels).
    if (!st.tablePreset || !sameShadingTable(*st.tablePreset, s.preset)) {
      st.tableVisibility = TableVisibility(table);
      ++st.tableGeneration;
    }
    glBindTexture(GL_TEXTURE_2D, st.table.id());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    // RGBA8: the software rasteriser filters 8-bit texels on its fast path, and 1/255 is finer than
    // any opacity step a preset can show.
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, table.dataSize, table.distanceSize, 0, GL_RGBA, GL_FLOAT,
                 table.rgba.data());
    table.rgba.clear();
    st.tableInfo = std::move(table);
    st.tablePreset = s.preset;
    st.tableStepMm = stepMm;
    st.tableRefMm = refMm;
    st.costs.tableMs += msSince(tableStart);
  }
  const TransferFunction2D& table = st.tableInfo;
  const bool bare = s.preset.mode == RenderMode::Bare;
  // Which blocks rays may skip. The key holds only what the grid depends on: with no context
  // (bare) no table, and with no field the CPU has seen (none, or one from CUDA) no distances, so
  // that a hover, which changes the context radius with the structure, keeps the structure-free
  // grid and only adds the structure to it.
  const bool fieldUsed = !bare && st.hasField && st.fieldOnCpu;
  OccupancyKey key;
  key.selected = st.selected;
  key.context = !bare;
  if (!bare) {
    key.tableGeneration = st.tableGeneration;
    key.surfaceLo = s.preset.surfaceGradientHu[0];
    key.surfaceFloor = s.preset.surfaceInterior > 0 || !(s.preset.surfaceGradientHu[1] > 0);
  }
  if (fieldUsed) {
    key.fieldGeneration = st.fieldGeneration;
    key.log2Alpha = std::log2(s.preset.alpha);
    key.distanceUnit = float(s.distanceUnit);
    key.distanceOffset = float(s.distanceOffset);
  }
  const Clock::time_point occupancyStart = Clock::now();
  const auto inputsFor = [&](const OccupancyKey& k) {
    OccupancyInputs in;
    in.blocks = &st.blocks;
    in.volumeGrid = &st.volumeGrid;
    in.table = k.context ? &st.tableVisibility : nullptr;
    in.surfaceLo = k.surfaceLo;
    in.surfaceFloor = k.surfaceFloor;
    in.field = k.fieldGeneration != 0 ? &st.fieldMinima : nullptr;
    in.log2Alpha = k.log2Alpha;
    in.distanceUnit = k.distanceUnit;
    in.distanceOffset = k.distanceOffset;
    return in;
  };
  const auto contextGrid = [&](const OccupancyKey& k) {
    std::vector<std::uint8_t> grid = computeOccupancy(inputsFor(k));
    addLeapDistances(st.blocks.blocks, grid);
    return grid;
  };
  OccupancyKey contextKey = key;  // the structure-free grid's: a hover only adds the structure
  contextKey.selected = 0;
  bool upload = !st.occupancyKey || !(*st.occupancyKey == key);
  const bool contextCurrent = st.contextKey && *st.contextKey == contextKey;
  const bool jobCurrent = st.occupancyJob && st.occupancyJob->key == contextKey;
  if (upload && !contextCurrent && !jobCurrent) {
    if (fieldUsed && interactive) {
      OccupancyKey freeKey = contextKey;
      freeKey.fieldGeneration = 0;
      freeKey.log2Alpha = freeKey.distanceUnit = freeKey.distanceOffset = 0;
      if (!st.fieldFreeKey || !(*st.fieldFreeKey == freeKey)) {
        st.fieldFreeOccupancy = contextGrid(freeKey);
        st.fieldFreeKey = freeKey;
      }
      st.contextOccupancy = st.fieldFreeOccupancy;
      st.contextKey = freeKey;
      st.occupancyJob = State::OccupancyJob{contextKey, 0, std::vector<std::uint8_t>(st.blocks.blocks.count(), 0)};
    } else {
      st.contextOccupancy = contextGrid(contextKey);
      st.contextKey = contextKey;
      st.occupancyJob.reset();
    }
  }
  if (st.occupancyJob && !(st.occupancyJob->key == contextKey)) st.occupancyJob.reset();  // stale
  if (st.occupancyJob) {
    State::OccupancyJob& job = *st.occupancyJob;
    const OccupancyInputs in = inputsFor(job.key);
    const int layers = st.blocks.blocks.z;
    while (job.nextLayer < layers && (!interactive || msSince(occupancyStart) < State::kOccupancyLayersMs)) {
      computeContextLayers(in, job.nextLayer, job.nextLayer + 1, job.grid);
      ++job.nextLayer;
    }
    if (job.nextLayer >= layers) {
      addLeapDistances(st.blocks.blocks, job.grid);
      st.contextOccupancy = std::move(job.grid);
      st.contextKey = job.key;
      st.occupancyJob.reset();
      upload = true;
    }
  }
  if (upload) {
    const std::vector<std::uint8_t> occ = withStructure(st.blocks, st.contextOccupancy, st.selected);
    const Dims& nb = st.blocks.blocks;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glBindTexture(GL_TEXTURE_3D, st.occupancy.id());
    glTexSubImage3D(GL_TEXTURE_3D, 0, 0, 0, 0, nb.x, nb.y, nb.z, GL_RED_INTEGER, GL_UNSIGNED_BYTE, occ.data());
    st.occupancyKey = key;
    if (auto e = glStatus("uploading the occupancy grid"); !e) return e;
  }
  st.costs.occupancyMs += msSince(occupancyStart);

  RayVariant variant;
  variant.mode = bare ? 1 : s.preset.mode == RenderMode::Lighting ? 2 : s.preset.mode == RenderMode::Outline ? 3 : 0;
  variant.shading = s.shading;
  variant.clip = s.clip.has_value();
  variant.structure = st.warmStructure >= 0 ? st.warmStructure == 1 : st.selected != 0;
  auto program = rayCasterProgram(st, st.rayCaster, variant);
  if (!program) return tl::unexpected(program.error());
  bool& used = (st.rayCaster == RayCaster::Compute ? st.computeUsed : st.fragmentUsed)[std::size_t(variant.index())];
  if (!used) ++st.costs.firstUses;
  used = true;
  const GLuint p = *program;
  glUseProgram(p);
  const auto loc = [p](const char* n) { return glGetUniformLocation(p, n); };
  const auto setMat = [&](const char* n, const Mat4& m) {
    const auto f = m.toFloat();
    glUniformMatrix4fv(loc(n), 1, GL_FALSE, f.data());
  };
  const Mat4 toTex = patientToTexture(st.volumeGrid);
  setMat("uInvViewProj", s.camera.viewProjection(double(s.width) / double(s.height)).inverse());
  setMat("uPatientToTex", toTex);
  setMat("uPatientToField", patientToTexture(st.hasField ? st.fieldGrid : st.volumeGrid));
  glUniform2f(loc("uViewport"), float(s.width), float(s.height));
  glUniform1i(loc("uHasField"), st.hasField ? 1 : 0);
  glUniform1f(loc("uStepMm"), float(stepMm));
  glUniform1f(loc("uStructureAlpha"), bare ? 1.0f : s.preset.structureOpacity);
  glUniform1f(loc("uMaskHalo"), kMaskHalo);
  glUniform1f(loc("uFrontFactor"), s.preset.contextInFront);
  {
    // The structure's box in texture coordinates (empty: no structure).
    const auto& box = st.maskBox;
    glUniform3f(loc("uMaskBoxLo"), float(box[0]) / float(vd.x), float(box[1]) / float(vd.y), float(box[2]) / float(vd.z));
    glUniform3f(loc("uMaskBoxHi"), float(box[3]) / float(vd.x), float(box[4]) / float(vd.y), float(box[5]) / float(vd.z));
  }
  glUniform1f(loc("uDistanceScale"), float(std::log2(double(s.preset.alpha)) / s.distanceUnit));
  glUniform1f(loc("uBandN"), outlineBandN(s.preset));
  glUniform1f(loc("uDistanceOffset"), float(s.distanceOffset));
  glUniform2f(loc("uDataRange"), float(table.dataMin), float(table.dataMax));
  const std::array<float, 2> visibleHu = st.tableVisibility.visibleHu();
  glUniform2f(loc("uVisibleHu"), visibleHu[0], visibleHu[1]);
  glUniform2f(loc("uTableSize"), float(table.dataSize), float(table.distanceSize));
  glUniform3f(loc("uSurface"), s.preset.surfaceGradientHu[0], s.preset.surfaceGradientHu[1], s.preset.surfaceInterior);
  glUniform1f(loc("uMaxStrength"), GradientVolume::kMaxHuPerVoxel);
  if (s.clip)
    glUniform4f(loc("uClip"), float(s.clip->normal[0]), float(s.clip->normal[1]), float(s.clip->normal[2]),
                float(s.clip->d));
  glUniform3f(loc("uHighlight"), s.preset.highlightRgb[0], s.preset.highlightRgb[1], s.preset.highlightRgb[2]);
  // Eq. 6 on D / (distanceUnit × lightingReach): lighting's α is in the distance TF's unit, the
  // reach (1 unless the picture chose another, picture_scale.h) lights farther.
  glUniform2f(loc("uLighting"), float(double(s.preset.lightingAlpha) / (s.distanceUnit * s.lightingReach)), s.preset.lightingBeta);
  // The key light: from the viewer, a little above and to the left, so that surfaces facing the
  // viewer are lit and their slopes read as shape.
  const Vec3 right = cross(s.camera.forward(), s.camera.up());
  const Vec3 toLight = -1.0 * s.camera.forward() + 0.7 * s.camera.up() - 0.45 * right;
  const double lightLen = norm(toLight);
  glUniform3f(loc("uLightDir"), float(toLight[0] / lightLen), float(toLight[1] / lightLen), float(toLight[2] / lightLen));
  glUniform3f(loc("uDims"), float(vd.x), float(vd.y), float(vd.z));
  glUniform1i(loc("uBlock"), kBlockVoxels);
  glUniform3i(loc("uBlocks"), st.blocks.blocks.x, st.blocks.blocks.y, st.blocks.blocks.z);
  glUniform1i(loc("uJitter"), s.jitter ? 1 : 0);
  glUniform1i(loc("uSkip"), s.skipEmptySpace ? 1 : 0);
  glUniform4f(loc("uBackground"), s.background[0], s.background[1], s.background[2], s.background[3]);
  const std::pair<const char*, std::pair<GLenum, GLuint>> textures[] = {
      {"uVolume", {GL_TEXTURE_3D, st.volume.id()}}, {"uMask", {GL_TEXTURE_3D, st.mask.id()}},
      {"uField", {GL_TEXTURE_3D, st.field.id()}},   {"uTable", {GL_TEXTURE_2D, st.table.id()}},
      {"uOccupancy", {GL_TEXTURE_3D, st.occupancy.id()}}};
  int unit = 0;
  for (const auto& [name, target] : textures) {
    glActiveTexture(GLenum(GL_TEXTURE0 + unit));
    glBindTexture(target.first, target.second);
    glUniform1i(loc(name), unit);
    ++unit;
  }
  glActiveTexture(GL_TEXTURE0);
  return glStatus("preparing the ray caster");
}

Status VolumeRenderer::draw(const RenderSettings& s, bool interactive) {
  if (auto e = prepare(s, interactive); !e) return e;
  State& st = *state_;
  if (st.fboWidth != s.width || st.fboHeight != s.height) {
    allocateImage(st, st.colour, s.width, s.height);
    glBindFramebuffer(GL_FRAMEBUFFER, st.fbo.id());
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, st.colour.id(), 0);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      return fail("render: the offscreen framebuffer is incomplete");
    st.fboWidth = s.width;
    st.fboHeight = s.height;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, st.fbo.id());
  glViewport(0, 0, s.width, s.height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  GLint program = 0;
  glGetIntegerv(GL_CURRENT_PROGRAM, &program);
  const auto loc = [program](const char* n) { return glGetUniformLocation(GLuint(program), n); };
  if (st.rayCaster == RayCaster::Compute) {
    // The whole image: level 0, every lattice point, tiles in order.
    glBindImageTexture(0, st.colour.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
    const int tilesWide = (s.width + 7) / 8, tiles = tilesWide * ((s.height + 7) / 8);
    glUniform1i(loc("uLevel"), 0);
    glUniform2i(loc("uSubStep"), 1, 1);
    glUniform2i(loc("uSubOffset"), 0, 0);
    glUniform1i(loc("uRankStart"), 0);
    glUniform1i(loc("uTilesWide"), tilesWide);
    glUniform1i(loc("uTiles"), tiles);
    glUniform1i(loc("uScramble"), 1);
    glDispatchCompute(GLuint(tiles), 1, 1);
    glMemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  } else {
    glBindVertexArray(st.vao.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  const Status drawn = glStatus("drawing");
  if (!drawn) forgetPrepared();
  return drawn;
}

Result<RgbaImage> VolumeRenderer::render(const RenderSettings& s) {
  if (auto st = draw(s, false); !st) return tl::unexpected(st.error());
  RgbaImage image(s.width, s.height);
  std::vector<std::uint8_t> rows(image.rgba.size());
  glBindFramebuffer(GL_FRAMEBUFFER, state_->fbo.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, s.width, s.height, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
  if (auto st = glStatus("reading the image back"); !st) return tl::unexpected(st.error());
  const std::size_t stride = std::size_t(s.width) * 4;
  for (int y = 0; y < s.height; ++y)  // GL's row 0 is the bottom
    std::copy_n(rows.data() + std::size_t(s.height - 1 - y) * stride, stride, image.rgba.data() + std::size_t(y) * stride);
  return image;
}

Result<double> VolumeRenderer::renderTimed(const RenderSettings& s) {
  glBeginQuery(GL_TIME_ELAPSED, state_->timer.id());
  const Status st = draw(s, false);
  glEndQuery(GL_TIME_ELAPSED);
  if (!st) return tl::unexpected(st.error());
  GLuint64 ns = 0;
  glGetQueryObjectui64v(state_->timer.id(), GL_QUERY_RESULT, &ns);
  return double(ns) * 1e-6;
}

}  // namespace at::render::gl
