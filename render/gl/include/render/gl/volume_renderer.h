// The GPU ray caster (ARCHITECTURE.md §4): HU, labels, the smoothed gradient volume and the
// distance field as 3-D textures, the mode's 2-D table as a texture, front-to-back compositing with
// empty-space skipping and early termination, jittered ray starts, context drawn as shaded
// surfaces, the selected structure from its mask and a clipping plane (render_settings.h documents
// the classification; CPU picking uses the same rules). Needs a current OpenGL 4.3 core context
// (EglContext or the desktop window's) for its whole life.
//
// Errors: a call that meets a GL error returns it (naming the step, or saying that the error was
// already pending from other GL code in the context) and leaves nothing half-made: the next call
// rebuilds what the failed one touched, so one error costs one frame, not every later one.
//
// Two ways to get an image:
//  - render(): the whole image in one draw, read back (the `render` command, tests, benchmarks);
//  - refine(): progressive refinement for an interactive view. Each call casts the rays that fit
//    in a time budget. Pixels are cast coarse-to-fine on lattices of stride 8, 4, 2, 1 (each
//    finer level casts only the points no coarser level has), rows of a level in an interleaved
//    order so that every call's rays spread over the image; every cast pixel is final (full
//    quality, shading included), so the image converges to exactly what render() gives for the
//    same settings. What to show (display()) is the finest complete lattice as a small texture,
//    stretched over the view with linear filtering: no pass over the full image per call. On a
//    GPU the whole image fits in one call's budget.
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "render/gradient_volume.h"
#include "render/image.h"
#include "render/render_settings.h"
#include "core/error.h"

namespace at::cuda {
class DeviceField;
}

namespace at::render::gl {

// Where the rays are cast: a compute shader (one invocation per pixel, the default) or a
// fragment shader over a full-screen triangle. Both run the same ray code and give the same
// image; the choice is for benchmarks. refine() always uses the compute shader.
enum class RayCaster { Compute, Fragment };

// Where a progressive image stands after a refine() call.
struct RefineProgress {
  bool restarted = false;   // this call began a new image (the settings or the scene changed)
  bool complete = false;    // every pixel is cast: the display image equals render()'s
  double fraction = 0;      // of the image's pixels cast so far
  bool displayable = false; // the coarsest lattice is complete: display() has an image
  int level = 3;            // finest complete lattice level: stride 2^level (0 when complete)
  double ms = 0;            // wall time this call took (GL finished)
  double imageMs = 0;       // wall time spent on this image so far, over all calls
  int calls = 0;            // refine() calls this image took so far
};

// The image to show for a progressive render: a texture of the finest complete lattice (an opaque
// handle, ImTextureID; RGBA8, straight alpha, bottom row first as GL stores it) and the texture
// coordinates to draw over the view's rectangle (its left/bottom and right/top edges), which put
// each lattice point's texel centre on the centre of the pixel it was cast for.
struct DisplayImage {
  std::uintptr_t handle = 0;   // 0: nothing to show yet
  int texelsWide = 0, texelsHigh = 0;
  std::array<float, 2> uv0{0, 0}, uv1{1, 1};
};

// What the preparation of the renderer's draws cost since the last takeCosts() (wall ms on the
// calling thread): the structure mask rebuilt on a selection change, the table texture, the
// empty-space grid, and whether a ray-caster variant was used for the first time (compiled, and
// on a software rasteriser translated to machine code at its first dispatch).
struct PrepareCosts {
  double prepareMs = 0;  // the whole preparation: the three below, the program and its uniforms
  double maskMs = 0, tableMs = 0, occupancyMs = 0;
  int firstUses = 0;  // variants dispatched for the first time
};

class VolumeRenderer {
 public:
  // Compiles the shaders. Errors carry the GLSL log.
  static Result<VolumeRenderer> create();
  ~VolumeRenderer();
  VolumeRenderer(VolumeRenderer&&) noexcept;
  VolumeRenderer& operator=(VolumeRenderer&&) noexcept;

  // Uploads HU, labels (on the volume's grid) and the gradient volume (computed here when not
  // given; pass the one the caller keeps for picking to avoid computing it twice). Replaces any
  // previous volume and drops the field.
  Status setVolume(const Volume& volume, const LabelMap& labels);
  Status setVolume(const Volume& volume, const LabelMap& labels, const GradientVolume& gradients);
  // The labels changed inside the voxel box {x0, y0, z0, x1, y1, z1} (min inclusive, max
  // exclusive; an edit of the label map on the volume's grid): that box of the label texture is
  // uploaded again, and the structure mask and the structure's blocks of the empty-space grid are
  // rebuilt at the next draw (the context's grid is kept: it does not depend on labels). The
  // field stays (the caller replaces a field the edit made stale). Errors: no volume, labels on
  // another grid.
  Status updateLabels(const LabelMap& labels, const std::array<int, 6>& box);
  // Uploads a distance field on its own grid (the volume's or a coarser one); +inf stays "far".
  Status setField(const FloatVolume& field);
  // Uploads `field` a few z-slices per call, for a frame loop that must not stall: software GL
  // takes ~0.2 s for a whole 256³ float field. Each call uploads slices until about `budgetMs` of
  // wall time has passed (at least one slice) into a second texture; the field shown (and
  // rendered) stays the previous one until the last slice is in, when the two textures swap and
  // the call returns true. The texture replaced is kept as the next upload's target; when none of
  // these dims exists, allocating it is the first call's only work. A call with another field
  // (another address or grid) starts over; the caller keeps `field` alive and unchanged until the
  // call that returns true. setVolume drops an upload in progress.
  Result<bool> uploadFieldStep(const FloatVolume& field, double budgetMs);
  // Copies a field that lives in CUDA device memory straight into the field texture (CUDA–GL
  // interop, no host round trip). Error when built without CUDA or when a CUDA call fails. Such
  // a field is not seen by the CPU, so empty-space skipping does not use its distances.
  Status setFieldFromDevice(const cuda::DeviceField& field);
  // Gives the field texture storage of `dims` registered with CUDA now, which the first device
  // field of those dims would otherwise do in its frame (~70-170 ms once). For a view that opens a
  // dataset whose fields will come from the GPU. True when done; false (nothing done) without
  // CUDA interop or a CUDA device, or while a field is shown.
  Result<bool> reserveDeviceField(const Dims& dims);
  // Whether this build has the interop path (AT_HAVE_CUDA).
  static bool hasCudaInterop();
  void clearField();
  // The structure drawn from its mask (0: none).
  void setSelected(std::uint16_t label);
  void setRayCaster(RayCaster rayCaster);

  // Renders one whole frame and reads it back.
  Result<RgbaImage> render(const RenderSettings& settings);
  // Renders one whole frame into a texture of the renderer that a UI draws directly (the
  // desktop's view: no read-back). The handle shows this frame until the next render or
  // renderToTexture call and stays a live texture until display() or renderToTexture() hands out
  // another (a UI may keep drawing it meanwhile); its uv0/uv1 are the image's left/bottom and
  // right/top.
  Result<DisplayImage> renderToTexture(const RenderSettings& settings);
  // Renders one whole frame without reading it back; returns the GPU time of the draw in ms
  // (GL_TIME_ELAPSED), for benchmarks.
  Result<double> renderTimed(const RenderSettings& settings);

  // Progressive refinement (see the top of this file). A call whose settings, volume, field or
  // selection differ from the previous call's starts a new image; `budgetMs` bounds the wall time
  // of the rays it casts, from the first call of an image on (each call casts at least one tile of
  // 64 rays; chunks are sized from the cost measured so far, or the previous image's).
  Result<RefineProgress> refine(const RenderSettings& settings, double budgetMs);
  // Runs every ray-caster variant an interactive view of `settings` may use (each of the shader's
  // modes, with and without a structure and shading, at the settings' clip) once on a few pixels, with the textures as they are: a
  // software rasteriser translates a variant to machine code at its first dispatch (0.1–1 s), which
  // a view wants done before its first frame. Leaves no image.
  Status warmUp(const RenderSettings& settings);
  // The preparation costs since the previous call (for the desktop's frame report).
  PrepareCosts takeCosts();

  // Nothing (handle 0) until the coarsest lattice is complete. The texture handed out stays live
  // (its contents may be refined further) until display() or renderToTexture() hands out another,
  // whatever the renderer reallocates meanwhile: a view can keep drawing what it was last given
  // while a new image of another size is not displayable yet.
  DisplayImage display();
  // What display() shows, as the view would (linear filtering), at the view's size, top row first:
  // for tests and screenshots.
  Result<RgbaImage> readDisplay();

  struct State;  // opaque: the GL objects, defined inside render/gl

 private:
  explicit VolumeRenderer(std::unique_ptr<State> state);
  // `interactive`: the refine/renderToTexture paths of a frame loop (renderer_state.h: OccupancyJob).
  Status prepare(const RenderSettings& settings, bool interactive);  // prepareState, timed into the costs
  Status prepareState(const RenderSettings& settings, bool interactive);
  Status draw(const RenderSettings& settings, bool interactive);
  // After a failed call: the mask, table, occupancy grid and progressive image are built again.
  void forgetPrepared();
  std::unique_ptr<State> state_;
};

}  // namespace at::render::gl
