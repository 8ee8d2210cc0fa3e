// Progressive refinement across frames (volume_renderer.h): casts lattice rows until the call's
// time budget is spent, then resolves the display image.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>

#include "render/gl/volume_renderer.h"
#include "renderer_state.h"

namespace at::render::gl {

namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

int ceilDiv(int a, int b) { return (a + b - 1) / b; }

// The tiles of one level: the coarsest level's whole lattice, or a finer level's two
// sub-lattices (its odd rows, then the odd points of its even rows), one after the other in rank
// order.
struct SubLattice {
  int stepX = 1, stepY = 1, offsetX = 0, offsetY = 0;
};

struct LevelTiles {
  std::array<SubLattice, 2> subs{};
  int subCount = 1;
  std::array<int, 2> tilesWide{}, tiles{};
  int total() const { return tiles[0] + (subCount > 1 ? tiles[1] : 0); }
};

LevelTiles levelTiles(int level, int width, int height) {
  LevelTiles t;
  const int columns = ceilDiv(width, 1 << level), rows = ceilDiv(height, 1 << level);
  if (level < ProgressiveImage::kCoarsestLevel) {
    t.subCount = 2;
    t.subs[0] = {1, 2, 0, 1};
    t.subs[1] = {2, 2, 1, 0};
  }
  for (int i = 0; i < t.subCount; ++i) {
    const SubLattice& s = t.subs[std::size_t(i)];
    t.tilesWide[std::size_t(i)] = ceilDiv(ceilDiv(columns - s.offsetX, s.stepX), 8);
    t.tiles[std::size_t(i)] = t.tilesWide[std::size_t(i)] * ceilDiv(ceilDiv(rows - s.offsetY, s.stepY), 8);
  }
  return t;
}

}  // namespace

Result<RefineProgress> VolumeRenderer::refine(const RenderSettings& s, double budgetMs) {
  const Clock::time_point start = Clock::now();
  State& st = *state_;
  ProgressiveImage& image = st.progressive;
  RefineProgress out;
  if (!image.active || !(image.settings == s) || image.sceneGeneration != st.sceneGeneration) {
    image = ProgressiveImage{};
    image.active = true;
    image.settings = s;
    image.sceneGeneration = st.sceneGeneration;
    out.restarted = true;
  }
  const auto report = [&]() {
    out.complete = image.level < 0;
    out.displayable = image.level < ProgressiveImage::kCoarsestLevel;
    out.level = std::max(0, image.level + 1);
    if (image.level == ProgressiveImage::kCoarsestLevel) out.level = ProgressiveImage::kCoarsestLevel;
    out.fraction = std::min(1.0, image.castPixels / (double(s.width) * double(s.height)));
    if (out.complete) out.fraction = 1.0;
    out.calls = image.calls;
    out.imageMs = image.imageMs;
    return out;
  };
  if (image.level < 0) {  // complete: the display image is final
    out.ms = msSince(start);
    return report();
  }
  const RayCaster kind = st.rayCaster;
  st.rayCaster = RayCaster::Compute;
  const Status prepared = prepare(s, true);
  st.rayCaster = kind;
  if (!prepared) return tl::unexpected(prepared.error());
  if (st.progressiveWidth != s.width || st.progressiveHeight != s.height) {
    for (int l = 0; l <= ProgressiveImage::kCoarsestLevel; ++l)
      allocateImage(st, st.levelImages[std::size_t(l)], ceilDiv(s.width, 1 << l), ceilDiv(s.height, 1 << l));
    st.progressiveWidth = s.width;
    st.progressiveHeight = s.height;
  }
  GLint program = 0;
  glGetIntegerv(GL_CURRENT_PROGRAM, &program);
  const auto loc = [program](const char* n) { return glGetUniformLocation(GLuint(program), n); };
  for (int l = 0; l <= ProgressiveImage::kCoarsestLevel; ++l)
    glBindImageTexture(GLuint(l), st.levelImages[std::size_t(l)].id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
  double castMs = 0;
  while (image.level >= 0) {
    const LevelTiles tiles = levelTiles(image.level, s.width, s.height);
    // Within one sub-lattice per dispatch.
    const int sub = image.ranksDone < tiles.tiles[0] ? 0 : 1;
    const int rankInSub = image.ranksDone - (sub == 0 ? 0 : tiles.tiles[0]);
    const int subTiles = tiles.tiles[std::size_t(sub)];
    int count = subTiles - rankInSub;
    const double left = budgetMs - msSince(start);
    if (left <= 0 && castMs > 0) break;
    // Chunks of at most a third of the budget, sized by the dearer of the image's average cost
    // per pixel and the last chunk's (tiles go in order, so neighbouring chunks cost alike and a
    // chunk moving into a dearer region is caught by the next one). A new image starts from the
    // previous image's cost; with none known, one tile measures it and chunks at most double
    // until their cost is known from enough rays (one tile may be all empty space).
    const bool measured = image.castPixels >= 64.0 * 16;
    const double perPixel = image.castPixels > 0 ? std::max(image.msPerPixel, image.lastMsPerPixel)
                                                 : st.refineMsPerPixel;
    if (perPixel > 0)
      count = std::clamp(int(std::floor(std::min(0.9 * left, budgetMs / 3.0) / (perPixel * 64.0))), 1, count);
    else
      count = 1;
    if (!measured && image.castPixels > 0) count = std::min(count, std::max(1, 2 * image.lastCount));
    image.lastCount = count;
    const SubLattice& lattice = tiles.subs[std::size_t(sub)];
    glUniform1i(loc("uLevel"), image.level);
    glUniform2i(loc("uSubStep"), lattice.stepX, lattice.stepY);
    glUniform2i(loc("uSubOffset"), lattice.offsetX, lattice.offsetY);
    glUniform1i(loc("uRankStart"), rankInSub);
    glUniform1i(loc("uTilesWide"), tiles.tilesWide[std::size_t(sub)]);
    glUniform1i(loc("uTiles"), subTiles);
    glUniform1i(loc("uScramble"), 1);
    const Clock::time_point dispatchStart = Clock::now();
    glDispatchCompute(GLuint(count), 1, 1);
    glFinish();
    const double ms = msSince(dispatchStart);
    castMs += ms;
    // The cost per pixel over this image so far (tiles of every level sample the whole image).
    const double before = image.castPixels;
    image.castPixels += 64.0 * count;
    image.msPerPixel = (image.msPerPixel * before + ms) / image.castPixels;
    image.lastMsPerPixel = ms / (64.0 * count);
    image.ranksDone += count;
    st.refineMsPerPixel = image.msPerPixel;
    if (image.ranksDone >= tiles.total()) {
      --image.level;
      image.ranksDone = 0;
    }
  }
  glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  if (auto e = glStatus("refining the progressive image"); !e) {
    forgetPrepared();  // the image starts over, on state built again
    return tl::unexpected(e.error());
  }
  ++image.calls;
  out.ms = msSince(start);
  image.imageMs += out.ms;
  return report();
}

DisplayImage VolumeRenderer::display() {
  State& st = *state_;
  const ProgressiveImage& image = st.progressive;
  DisplayImage out;
  if (!image.active || image.level >= ProgressiveImage::kCoarsestLevel) return out;
  const int level = image.level + 1;
  const int stride = 1 << level;
  const int w = st.progressiveWidth, h = st.progressiveHeight;
  out.handle = std::uintptr_t(st.levelImages[std::size_t(level)].id());
  handOut(st, st.levelImages[std::size_t(level)].id());
  out.texelsWide = ceilDiv(w, stride);
  out.texelsHigh = ceilDiv(h, stride);
  // Texel u's centre on the centre of pixel u · stride: tex(x) = ((x − 0.5) / stride + 0.5) / texels.
  const auto edge = [stride](double x, int texels) { return float(((x - 0.5) / stride + 0.5) / texels); };
  out.uv0 = {edge(0, out.texelsWide), edge(0, out.texelsHigh)};
  out.uv1 = {edge(w, out.texelsWide), edge(h, out.texelsHigh)};
  return out;
}

Result<RgbaImage> VolumeRenderer::readDisplay() {
  const DisplayImage shown = display();
  if (!shown.handle) return fail("render: no progressive image to show yet (call refine first)");
  const int tw = shown.texelsWide, th = shown.texelsHigh;
  std::vector<std::uint8_t> texels(std::size_t(tw) * std::size_t(th) * 4);
  glBindTexture(GL_TEXTURE_2D, GLuint(shown.handle));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, texels.data());
  if (auto e = glStatus("reading the progressive image back"); !e) return tl::unexpected(e.error());
  // Linear filtering as the view samples the texture (GL rows bottom first; the image top first).
  const int w = state_->progressiveWidth, h = state_->progressiveHeight;
  RgbaImage out(w, h);
  const auto coordinate = [](double uv, int texels) { return std::clamp(uv * texels - 0.5, 0.0, double(texels - 1)); };
  for (int y = 0; y < h; ++y) {
    const double v = shown.uv0[1] + (shown.uv1[1] - shown.uv0[1]) * ((h - 1 - y) + 0.5) / h;
    const double ty = coordinate(v, th);
    const int y0 = int(ty), y1 = std::min(y0 + 1, th - 1);
    const double fy = ty - y0;
    for (int x = 0; x < w; ++x) {
      const double u = shown.uv0[0] + (shown.uv1[0] - shown.uv0[0]) * (x + 0.5) / w;
      const double tx = coordinate(u, tw);
      const int x0 = int(tx), x1 = std::min(x0 + 1, tw - 1);
      const double fx = tx - x0;
      for (int c = 0; c < 4; ++c) {
        const auto at = [&](int i, int j) { return double(texels[(std::size_t(j) * std::size_t(tw) + std::size_t(i)) * 4 + std::size_t(c)]); };
        const double value = (at(x0, y0) * (1 - fx) + at(x1, y0) * fx) * (1 - fy) + (at(x0, y1) * (1 - fx) + at(x1, y1) * fx) * fy;
        out.rgba[(std::size_t(y) * std::size_t(w) + std::size_t(x)) * 4 + std::size_t(c)] = std::uint8_t(std::lround(value));
      }
    }
  }
  return out;
}

}  // namespace at::render::gl
