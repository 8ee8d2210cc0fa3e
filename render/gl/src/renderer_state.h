// The ray caster's GL state, shared by volume_renderer.cpp (uploads, whole frames) and
// progressive.cpp (refinement across frames). Internal to render/gl.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "gl_objects.h"
#include "occupancy.h"
#include "render/gl/volume_renderer.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/gl_interop.h"
#endif

namespace at::render::gl {

// What a ray caster program is specialised to (compile-time constants of the shader, so that
// per-sample branches and the unused modes' code leave the program).
struct RayVariant {
  static constexpr int kModes = 4;
  static constexpr int kCount = kModes * 8;
  // 0 table (WDT, non-weighted, fuzzy), 1 bare, 2 lighting, 3 outline (a table mode whose samples
  // also look for the band over their step: only its program pays for that branch).
  int mode = 0;
  bool shading = true, clip = false, structure = false;
  int index() const {
    return mode + kModes * ((shading ? 1 : 0) + 2 * (clip ? 1 : 0) + 4 * (structure ? 1 : 0));
  }
  std::string defines() const;
};

// Everything the occupancy grid depends on besides the volume.
struct OccupancyKey {
  std::uint64_t tableGeneration = 0, fieldGeneration = 0;
  std::uint16_t selected = 0;
  bool context = true;
  float surfaceLo = 0;
  bool surfaceFloor = false;
  float log2Alpha = 0, distanceUnit = 0, distanceOffset = 0;
  bool operator==(const OccupancyKey&) const = default;
};

// Progressive refinement of one image (volume_renderer.h): lattice levels from kCoarsestLevel to
// 0; the coarsest level in tiles of 8 × 8 lattice points, each finer one in two sub-lattices (the
// points no coarser level holds) of such tiles, tiles in order (ray_shaders.cpp): neighbouring
// tiles share the texels they read, which a software rasteriser's caches reward.
struct ProgressiveImage {
  static constexpr int kCoarsestLevel = 3;
  bool active = false;
  RenderSettings settings;
  std::uint64_t sceneGeneration = 0;
  int level = kCoarsestLevel;  // being cast; -1 when complete
  int ranksDone = 0;           // tiles of `level` cast so far (over its sub-lattices)
  double castPixels = 0;       // pixels cast so far (counting skipped lattice points of coarser levels)
  double msPerPixel = 0;       // measured on this image …
  double lastMsPerPixel = 0;   // … and on its last chunk
  double imageMs = 0;
  int calls = 0;
  int lastCount = 0;           // tiles in the last chunk
};

struct VolumeRenderer::State {
  std::array<Program, RayVariant::kCount> fragmentRayCasters, computeRayCasters;
  std::array<bool, RayVariant::kCount> computeUsed{}, fragmentUsed{};  // dispatched at least once
  PrepareCosts costs;  // since the last takeCosts()
  int warmStructure = -1;  // warmUp: the structure flag of the variant to run (-1: from the selection)
  Program maskProgram;
  VertexArray vao;
  Texture labels, field, table, mask, volume, occupancy;
  // uploadFieldStep: the texture being filled, what it is filled from and the next z-slice.
  Texture pendingField;
  Dims pendingDims;   // of pendingField's storage (zero: none)
  // Field textures of other dims kept for later uploads (the desktop alternates a coarse and the
  // full-resolution field), at most kSpareFields, the oldest dropped first.
  static constexpr std::size_t kSpareFields = 2;
  std::vector<std::pair<Dims, Texture>> spareFields;
  Dims fieldDims;     // of field's storage
  const float* pendingSource = nullptr;
  Geometry pendingGrid;
  int pendingNextSlice = 0;
  FieldBlockMinima pendingMinima, fieldMinima;  // distance minima of the pending and shown fields
  // The mask texture: which label it holds, in which box of voxels (min, max exclusive).
  int maskLabel = -1;  // -1: stale
  std::array<int, 6> maskBox{0, 0, 0, 0, 0, 0};
  std::uint16_t selected = 0;
  std::optional<Preset> tablePreset;       // a preset with the table texture's shadingTable …
  double tableStepMm = 0, tableRefMm = 0;  // … and the step its opacities are corrected to
  TransferFunction2D tableInfo;            // its axes (rgba dropped after upload)
  TableVisibility tableVisibility;
  std::uint64_t tableGeneration = 0;       // bumped when tableVisibility changes
  BlockSummary blocks;
  std::optional<OccupancyKey> occupancyKey;  // of the grid in the occupancy texture
  std::optional<OccupancyKey> contextKey;    // of contextOccupancy (selected 0)
  // The grid of occupancyKey's inputs with no structure (leaps added): a selection change (a
  // hover) only adds the structure to it (withStructure) instead of recomputing the whole grid.
  std::vector<std::uint8_t> contextOccupancy;
  // Interactive draws (refine, renderToTexture) do not compute the grid with a CPU field's
  // distances in the call that changed them (25–80 ms for a 64³ grid on the 2-core machine): they
  // use the grid without distances, which skips less but never wrongly, and compute the field's
  // grid kOccupancyLayersMs per call, a few z-layers at a time, then swap it in.
  static constexpr double kOccupancyLayersMs = 4;
  struct OccupancyJob {
    OccupancyKey key;  // selected 0
    int nextLayer = 0;
    std::vector<std::uint8_t> grid;
  };
  std::optional<OccupancyJob> occupancyJob;
  std::optional<OccupancyKey> fieldFreeKey;  // the grid without distances (leaps added), kept
  std::vector<std::uint8_t> fieldFreeOccupancy;
  // Bumped when the volume, the field or the selection changes (a progressive image of an older
  // scene starts over); fieldGeneration only when the field does (the occupancy's distances).
  std::uint64_t sceneGeneration = 0, fieldGeneration = 0;
  Framebuffer fbo;
  Texture colour;  // RGBA8, the framebuffer's attachment and the compute path's image
  int fboWidth = 0, fboHeight = 0;
  // Progressive refinement: one image per lattice level (level l: ceil(size / 2^l) texels).
  std::array<Texture, ProgressiveImage::kCoarsestLevel + 1> levelImages;
  int progressiveWidth = 0, progressiveHeight = 0;
  ProgressiveImage progressive;
  double refineMsPerPixel = 0;  // the last progressive image's cost, where the next one starts
  // The texture last handed out by display() or renderToTexture(): a UI draws it until another is
  // handed out, so a reallocation (another image size) moves it to `retired` instead of deleting it
  // (a UI binding a deleted name raises GL_INVALID_OPERATION in its own draw, every frame).
  GLuint handedOut = 0;
  Texture retired;
  RayCaster rayCaster = RayCaster::Compute;
  Query timer;
  Geometry volumeGrid, fieldGrid;
  bool hasVolume = false, hasField = false, fieldOnCpu = false;
#if defined(AT_HAVE_CUDA)
  std::optional<cuda::GlTextureTarget> interop;  // registered field texture storage
  Dims interopDims;
#endif
};

// "GL_INVALID_OPERATION", or the code in hex for one without a name here.
std::string glErrorName(GLenum error);
// Reads the GL error flag before the renderer's own calls: an error raised by other GL code in
// the context (a UI's draw), named as such rather than reported as the renderer's.
Status pendingGlError(const char* what);
// Reads the GL error flag: an error naming `what` when one is set.
Status glStatus(const char* what);
Result<Program> linkCompute(const char* source, const char* what);
// (Re)allocates one of the renderer's RGBA8 image textures with immutable storage; the one it
// replaces is kept alive (as `retired`) when it is the one handed out.
void allocateImage(VolumeRenderer::State& st, Texture& texture, int width, int height);
// Records that `texture` is handed out to the caller (what it shows now); a retired texture
// other than it is released.
void handOut(VolumeRenderer::State& st, GLuint texture);

}  // namespace at::render::gl
