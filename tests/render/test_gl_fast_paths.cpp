// The ray caster's fast paths keep the image: jumping over empty blocks skips only samples that
// would have classified to zero opacity, and the compute and fragment shader stages run the same rays.
#include <doctest/doctest.h>
#include <epoxy/gl.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <random>

#include "render/gl/volume_renderer.h"
#include "render_fixture.h"
#include "test_support.h"

using namespace at;
using namespace at::render;

namespace {

// Air with random blobs of soft tissue and bone, some one voxel thin and on block boundaries, a
// labelled structure among them and a distance field from its centre: a scene with empty blocks
// next to visible ones everywhere.
struct RandomScene {
  Volume volume;
  LabelMap labels;
  FloatVolume field;
  Vec3 structureCentreMm;  // the centre of label 7's blob, wholly inside the volume
};

RandomScene randomScene(std::mt19937_64& rng) {
  Geometry g;
  g.dims = {61, 53, 67};  // not multiples of the block edge
  g.spacingMm = {0.3, 0.35, 0.27};
  g.originMm = {-9, -9.1, -8.9};
  RandomScene s{Volume(g, -1000), LabelMap(g, 0), FloatVolume(g, 0.0f), {}};
  std::uniform_int_distribution<int> ix(0, g.dims.x - 1), iy(0, g.dims.y - 1), iz(0, g.dims.z - 1);
  std::uniform_int_distribution<int> radius(0, 3), hu(-50, 1800);
  // Blob 0 is the structure: large enough for bare mode's mask to cross 0.5, and wholly inside the
  // volume so that every camera aimed at its centre sees it.
  constexpr int structureRadius = 3;
  std::uniform_int_distribution<int> sx(structureRadius, g.dims.x - 1 - structureRadius),
      sy(structureRadius, g.dims.y - 1 - structureRadius), sz(structureRadius, g.dims.z - 1 - structureRadius);
  for (int b = 0; b < 6; ++b) {
    const bool structure = b == 0;
    const int cx = structure ? sx(rng) : ix(rng), cy = structure ? sy(rng) : iy(rng), cz = structure ? sz(rng) : iz(rng);
    const int r = structure ? structureRadius : radius(rng);
    if (structure) s.structureCentreMm = g.indexToPatient({double(cx), double(cy), double(cz)});
    const auto v = std::int16_t(b == 0 ? 40 : hu(rng));
    for (int k = std::max(0, cz - r); k <= std::min(g.dims.z - 1, cz + r); ++k)
      for (int j = std::max(0, cy - r); j <= std::min(g.dims.y - 1, cy + r); ++j)
        for (int i = std::max(0, cx - r); i <= std::min(g.dims.x - 1, cx + r); ++i) {
          s.volume.at(i, j, k) = v;
          if (b == 0) s.labels.at(i, j, k) = 7;
        }
  }
  // Single bright voxels on the block edges (indices 7, 8, 15, 16 …).
  for (int i = 7; i + 1 < g.dims.x; i += 16) s.volume.at(i, 8, 16) = 1500;
  for (int k = 8; k + 1 < g.dims.z; k += 24) s.volume.at(40, 31, k) = 1500;
  const Vec3 centre = g.indexToPatient({double(g.dims.x) / 2, double(g.dims.y) / 2, double(g.dims.z) / 2});
  for (int k = 0; k < g.dims.z; ++k)
    for (int j = 0; j < g.dims.y; ++j)
      for (int i = 0; i < g.dims.x; ++i)
        s.field.at(i, j, k) = float(norm(g.indexToPatient({double(i), double(j), double(k)}) - centre));
  return s;
}

// Uploads `scene` (its field too) and selects its structure (label 7).
void upload(gl::VolumeRenderer& gl, const RandomScene& scene) {
  REQUIRE(gl.setVolume(scene.volume, scene.labels));
  REQUIRE(gl.setField(scene.field));
  gl.setSelected(7);
}

// A pixel-unpack buffer of 16 bytes, bound while it lives: a texture upload from client memory
// then reads past its end, so the renderer's own upload call raises GL_INVALID_OPERATION.
struct TooSmallUnpackBuffer {
  GLuint id = 0;
  TooSmallUnpackBuffer() {
    glGenBuffers(1, &id);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, id);
    glBufferData(GL_PIXEL_UNPACK_BUFFER, 16, nullptr, GL_STATIC_DRAW);
  }
  ~TooSmallUnpackBuffer() {
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
    glDeleteBuffers(1, &id);
  }
  TooSmallUnpackBuffer(const TooSmallUnpackBuffer&) = delete;
  TooSmallUnpackBuffer& operator=(const TooSmallUnpackBuffer&) = delete;
};

int maxChannelDiff(const RgbaImage& a, const RgbaImage& b) {
  int worst = 0;
  for (std::size_t i = 0; i < a.rgba.size(); ++i) worst = std::max(worst, std::abs(int(a.rgba[i]) - int(b.rgba[i])));
  return worst;
}

}  // namespace

TEST_CASE("Skipping empty blocks and the fragment stage give the image of marching every sample") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  std::mt19937_64 rng(test::freshSeed("gl_fast_paths"));
  const RandomScene scene = randomScene(rng);
  upload(*gl, scene);
  std::uniform_real_distribution<double> angle(-180, 180);
  for (RenderMode mode : {RenderMode::Wdt, RenderMode::Bare, RenderMode::Lighting}) {
    for (int view = 0; view < 3; ++view) {
      RenderSettings s;
      s.width = 48;
      s.height = 40;
      s.preset.mode = mode;
      s.preset.t = 0.5f;
      // Aimed at the structure, so that bare mode (the structure alone) always has something to draw.
      s.camera = Camera::named(NamedView::Anterior, scene.structureCentreMm, 12);
      s.camera.orbit(angle(rng), angle(rng) / 4);
      CAPTURE(int(mode));
      CAPTURE(view);
      s.skipEmptySpace = false;
      gl->setRayCaster(gl::RayCaster::Compute);
      auto every = gl->render(s);
      REQUIRE_MESSAGE(every, every.error().message);
      s.skipEmptySpace = true;
      auto skipping = gl->render(s);
      REQUIRE(skipping);
      gl->setRayCaster(gl::RayCaster::Fragment);
      auto fragment = gl->render(s);
      gl->setRayCaster(gl::RayCaster::Compute);
      REQUIRE(fragment);
      std::size_t drawn = 0;
      for (std::size_t i = 3; i < every->rgba.size(); i += 4) drawn += every->rgba[i] > 0;
      CHECK(drawn > 0);  // the view shows something, so the comparison means something
      CHECK(maxChannelDiff(*every, *skipping) <= 1);
      CHECK(maxChannelDiff(*every, *fragment) <= 1);
    }
  }
}

TEST_CASE("A field uploaded slice by slice keeps the old field on screen until it is complete, then renders as one uploaded at once") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  std::mt19937_64 rng(test::freshSeed("gl_field_steps"));
  const RandomScene scene = randomScene(rng);
  REQUIRE(gl->setVolume(scene.volume, scene.labels));
  gl->setSelected(7);
  // Two different fields on the volume's grid: distance from the centre, and from a corner.
  const FloatVolume& first = scene.field;
  FloatVolume second = scene.field;
  const Geometry& g = second.geometry;
  const Vec3 corner = g.indexToPatient({0, 0, 0});
  for (int k = 0; k < g.dims.z; ++k)
    for (int j = 0; j < g.dims.y; ++j)
      for (int i = 0; i < g.dims.x; ++i)
        second.at(i, j, k) = float(norm(g.indexToPatient({double(i), double(j), double(k)}) - corner));
  second.at(3, 4, 5) = std::numeric_limits<float>::infinity();  // unreachable voxels upload too

  RenderSettings s;
  s.width = 48;
  s.height = 40;
  s.preset.mode = RenderMode::Wdt;
  s.preset.t = 0.0f;  // only what the field reaches shows: the two fields give different images
  s.preset.surfaceGradientHu = {0, 0};  // every voxel the field reaches, not only edges: the blobs
  s.preset.surfaceInterior = 1;         // are a few voxels wide
  // Context from far to near, so that every blob's look depends on the field's value there.
  s.preset.distanceTf = {{0, {1, 1, 1, 0}}, {0.35, {1, 1, 1, 1}}, {1, {1, 0.5f, 0, 1}}};
  s.preset.alpha = 1.2f;
  s.preset.contextInFront = 1;
  // A view in which the two fields tell apart in the image. A random orbit of a random scene can
  // show none of the voxels where they differ (seed 25806670135292 did), so orbits are drawn until
  // one does.
  Result<RgbaImage> atOnce = at::fail("not rendered"), before = at::fail("not rendered");
  for (int tries = 0; tries < 16; ++tries) {
    s.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 12);
    s.camera.orbit(std::uniform_real_distribution<double>(-180, 180)(rng), 10);
    REQUIRE(gl->setField(second));
    atOnce = gl->render(s);
    REQUIRE(atOnce);
    REQUIRE(gl->setField(first));
    before = gl->render(s);
    REQUIRE(before);
    if (maxChannelDiff(*atOnce, *before) > 8) break;
  }
  REQUIRE(maxChannelDiff(*atOnce, *before) > 8);

  // A zero budget uploads one slice per call into the second texture (setVolume made one on the
  // volume's grid, so no call only allocates): dims.z calls, the old field shown until the last.
  int calls = 0;
  for (;;) {
    auto done = gl->uploadFieldStep(second, 0.0);
    REQUIRE_MESSAGE(done, done.error().message);
    ++calls;
    if (*done) break;
    if (calls == 1 || calls == g.dims.z / 2) {
      auto during = gl->render(s);
      REQUIRE(during);
      CHECK(maxChannelDiff(*during, *before) == 0);
    }
    REQUIRE(calls <= g.dims.z);
  }
  CHECK(calls == g.dims.z);
  auto after = gl->render(s);
  REQUIRE(after);
  CHECK(maxChannelDiff(*after, *atOnce) == 0);

  // Another field part-way through starts over; with the spare texture left by the swap there is
  // nothing to allocate, and a generous budget finishes in one call.
  REQUIRE(gl->uploadFieldStep(first, 0.0).value() == false);
  auto restarted = gl->uploadFieldStep(second, 1e6);
  REQUIRE(restarted);
  CHECK(*restarted);
  auto again = gl->render(s);
  REQUIRE(again);
  CHECK(maxChannelDiff(*again, *atOnce) == 0);

  // An error other GL code left pending is reported as not the upload's, and the upload is not
  // touched: the next call sends the whole field.
  REQUIRE(gl->setField(first));
  glBindTexture(GLenum(0x1234), 0);  // GL_INVALID_ENUM
  auto notOurs = gl->uploadFieldStep(second, 1e6);
  REQUIRE_FALSE(notOurs.has_value());
  CHECK(notOurs.error().message.find("raised before the field upload") != std::string::npos);
  auto sent = gl->uploadFieldStep(second, 1e6);
  REQUIRE_MESSAGE(sent, sent.error().message);
  CHECK(*sent);
  auto afterPending = gl->render(s);
  REQUIRE(afterPending);
  CHECK(maxChannelDiff(*afterPending, *atOnce) == 0);

  // A call that fails in its own GL calls (here a too small pixel-unpack buffer the test leaves
  // bound) leaves no upload half-done: the next call sends the field again from its first slice
  // and never reads past its last (it once went on one slice past the end: a heap overflow under
  // sanitize.sh, a crash in the desktop).
  REQUIRE(gl->setField(first));
  auto failed = [&] {
    const TooSmallUnpackBuffer tooSmall;
    return gl->uploadFieldStep(second, 1e6);
  }();
  REQUIRE_FALSE(failed.has_value());
  CHECK(failed.error().message.find("during uploading the distance field") != std::string::npos);
  // The failed call's texture is not reused: one call allocates a fresh one, the next uploads all.
  int retries = 0;
  for (bool done = false; !done && retries < 3; ++retries) {
    auto retried = gl->uploadFieldStep(second, 1e6);
    REQUIRE_MESSAGE(retried, retried.error().message);
    done = *retried;
  }
  CHECK(retries == 2);
  auto afterRetry = gl->render(s);
  REQUIRE(afterRetry);
  CHECK(maxChannelDiff(*afterRetry, *atOnce) == 0);

  // The whole-field upload still works on the swapped-in texture.
  REQUIRE(gl->setField(first));
  auto back = gl->render(s);
  REQUIRE(back);
  CHECK(maxChannelDiff(*back, *before) == 0);
}

TEST_CASE("Progressive refinement casts a bounded chunk per call, shows nothing before its coarsest lattice, and converges to render()'s image") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  std::mt19937_64 rng(test::freshSeed("gl_progressive"));
  const RandomScene scene = randomScene(rng);
  upload(*gl, scene);
  RenderSettings s;
  s.width = 130;  // the coarsest lattice (stride 8) is 17 × 13 points: 6 tiles of 8 × 8
  s.height = 100;
  s.preset.mode = RenderMode::Wdt;
  s.preset.t = 0.5f;
  s.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 12);
  s.camera.orbit(std::uniform_real_distribution<double>(-180, 180)(rng), 10);
  auto whole = gl->render(s);
  REQUIRE(whole);

  // A zero budget: each call casts one tile (64 rays), the least a call does.
  auto first = gl->refine(s, 0.0);
  REQUIRE(first);
  CHECK(first->restarted);
  CHECK_FALSE(first->displayable);
  CHECK_FALSE(first->complete);
  CHECK(gl->display().handle == 0);
  CHECK(first->fraction == doctest::Approx(64.0 / (130.0 * 100.0)));
  int calls = 1, coarsestAfter = 0;
  double fraction = first->fraction;
  Result<gl::RefineProgress> p = first;
  while (!p->complete && calls < 100000) {
    p = gl->refine(s, 0.0);
    REQUIRE(p);
    ++calls;
    CHECK_FALSE(p->restarted);
    CHECK(p->fraction >= fraction);
    fraction = p->fraction;
    if (p->displayable && !coarsestAfter) {
      coarsestAfter = calls;
      CHECK(gl->display().handle != 0);
    }
  }
  REQUIRE(p->complete);
  CHECK(coarsestAfter == 6);
  CHECK(calls >= (130 * 100) / 64);  // every call cast at most one tile
  auto shown = gl->readDisplay();
  REQUIRE(shown);
  std::size_t drawn = 0;
  for (std::size_t i = 3; i < whole->rgba.size(); i += 4) drawn += whole->rgba[i] > 0;
  CHECK(drawn > 0);
  CHECK(maxChannelDiff(*whole, *shown) <= 1);

  // Another view starts a new image; a generous budget completes it in one call.
  s.camera.orbit(30, 0);
  auto again = gl->refine(s, 1e9);
  REQUIRE(again);
  CHECK(again->restarted);
  CHECK(again->complete);
}

TEST_CASE("The image a view was handed stays a live texture while a new image of another size is not displayable yet") {
  // The desktop draws the last image display() or renderToTexture() handed it until refine()
  // gives a sharper one. refine() at another size (a rest that restarts smaller, a resized
  // window) used to delete the level textures at once: the view then bound a deleted name
  // (GL_INVALID_OPERATION in the UI's draw, every frame, which every later renderer call reported
  // as its own error: the CPU desktop's hover sweep, about 1 run in 3).
  auto* gl = test::glRenderer();
  if (!gl) return;
  std::mt19937_64 rng(test::freshSeed("gl_handed_out"));
  const RandomScene scene = randomScene(rng);
  upload(*gl, scene);
  RenderSettings s;
  s.width = 130;
  s.height = 100;
  s.preset.mode = RenderMode::Wdt;
  s.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 12);
  const auto isLiveTexture = [](std::uintptr_t handle) {
    glGetError();
    glBindTexture(GL_TEXTURE_2D, GLuint(handle));
    const GLenum bound = glGetError();
    glBindTexture(GL_TEXTURE_2D, 0);
    return bound == GL_NO_ERROR && glIsTexture(GLuint(handle)) == GL_TRUE;
  };
  for (int round = 0; round < 3; ++round) {
    auto complete = gl->refine(s, 1e9);
    REQUIRE(complete);
    REQUIRE(complete->complete);
    const gl::DisplayImage shown = gl->display();
    REQUIRE(shown.handle != 0);
    auto before = gl->readDisplay();
    REQUIRE(before);
    // Smaller, then larger again: each new size casts one tile, not yet a displayable image.
    s.width = round == 1 ? 130 : 70 + 10 * round;
    s.height = round == 1 ? 100 : 50 + 10 * round;
    auto started = gl->refine(s, 0.0);
    REQUIRE_MESSAGE(started, started.error().message);
    CHECK(started->restarted);
    CHECK_FALSE(started->displayable);
    CHECK(isLiveTexture(shown.handle));
    // A whole frame into the renderer's texture at yet another size keeps it too.
    RenderSettings other = s;
    other.width += 3;
    auto frame = gl->renderToTexture(other);
    REQUIRE_MESSAGE(frame, frame.error().message);
    CHECK(isLiveTexture(frame->handle));
    CHECK(isLiveTexture(shown.handle) == (frame->handle == shown.handle));  // released once another is handed out
    auto next = gl->refine(s, 0.0);
    REQUIRE(next);
    CHECK(isLiveTexture(frame->handle));  // the frame's texture is what the view shows now
  }
}

TEST_CASE("A frame that meets a GL error fails alone: the next frame rebuilds what it touched and equals a fresh render") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  std::mt19937_64 rng(test::freshSeed("gl_recovery"));
  const RandomScene scene = randomScene(rng);
  upload(*gl, scene);
  RenderSettings a;
  a.width = 64;
  a.height = 48;
  a.preset.mode = RenderMode::Wdt;
  a.preset.t = 0.5f;
  a.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 12);
  a.camera.orbit(std::uniform_real_distribution<double>(-180, 180)(rng), 10);
  RenderSettings b = a;  // another table: context far out, in another colour
  b.preset.t = 1.0f;
  b.preset.distanceTf = {{0, {0.2f, 0.9f, 0.3f, 1}}, {1, {0.2f, 0.9f, 0.3f, 1}}};
  b.preset.surfaceGradientHu = {0, 0};
  b.preset.surfaceInterior = 1;
  auto expectedB = gl->render(b);
  REQUIRE(expectedB);
  auto expectedA = gl->render(a);
  REQUIRE(expectedA);
  REQUIRE(maxChannelDiff(*expectedA, *expectedB) > 8);

  // An error other GL code left pending fails the next call, named as not the renderer's; the
  // call after it renders as before.
  glBindTexture(GLenum(0x1234), 0);  // GL_INVALID_ENUM
  auto notOurs = gl->refine(a, 1e9);
  REQUIRE_FALSE(notOurs.has_value());
  CHECK(notOurs.error().message.find("raised before this frame's render") != std::string::npos);
  auto refined = gl->refine(a, 1e9);
  REQUIRE_MESSAGE(refined, refined.error().message);
  CHECK(refined->complete);
  auto shownA = gl->readDisplay();
  REQUIRE(shownA);
  CHECK(maxChannelDiff(*shownA, *expectedA) <= 1);

  // A frame whose own uploads fail (the table and occupancy grid of b, with a too small
  // pixel-unpack buffer left bound): the next frame builds them again rather than taking the
  // failed upload for b's (which drew b with a's table: the old code).
  auto failed = [&] {
    const TooSmallUnpackBuffer tooSmall;
    return gl->refine(b, 1e9);
  }();
  REQUIRE_FALSE(failed.has_value());
  CHECK(failed.error().message.find("GL: error GL_INVALID_OPERATION during") != std::string::npos);
  auto recovered = gl->refine(b, 1e9);
  REQUIRE_MESSAGE(recovered, recovered.error().message);
  CHECK(recovered->complete);
  auto shownB = gl->readDisplay();
  REQUIRE(shownB);
  CHECK(maxChannelDiff(*shownB, *expectedB) <= 1);
  auto whole = gl->render(b);
  REQUIRE(whole);
  CHECK(maxChannelDiff(*whole, *expectedB) == 0);
}
