#include "render/gl/volume_renderer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "gl_objects.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/gl_interop.h"
#include "cuda/wdt_cuda.h"
#endif

namespace at::render::gl {

namespace {

constexpr int kOccupancyStale = -2, kOccupancyTable = -1;

const char* kVertexShader = R"(#version 430 core
void main() {
  // One triangle covering the viewport.
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

// Classification and shading as render_settings.h documents; keep in step with pick(). The table's
// opacities are already corrected to the step (baked on the CPU), normals come from a volume
// computed once per volume, and rays jump over blocks the occupancy grid marks empty: such a
// block holds no sample that can classify to a non-zero opacity, so jumping keeps the image.
// castRay(pixel centre in window coordinates) is the whole ray; the fragment and compute entry
// points below only differ in how they reach a pixel.
const char* kRayCaster = R"(
uniform mat4 uInvViewProj;
uniform mat4 uPatientToTex;
uniform mat4 uPatientToField;
uniform vec2 uViewport;
uniform sampler3D uHu;
uniform sampler3D uMask;
uniform sampler3D uField;
uniform sampler3D uNormals;     // unit HU gradient direction (RGBA8 snorm), zero where flat
uniform usampler3D uOccupancy;  // 1 per block that may hold a visible sample
uniform sampler2D uTable;       // RGBA, alpha corrected to the step
// Defined ahead of this source, one program per combination: RAY_MODE 0 table, 1 bare, 2 lighting;
// RAY_SHADING 0/1; RAY_CLIP 0/1 (a clipping plane is set).
uniform int uHasField;
uniform float uStepMm;
uniform float uBareAlpha;   // the bare mode's opaque sample, corrected to the step
uniform float uLog2Alpha;
uniform vec2 uDataRange;
uniform vec2 uVisibleHu;    // table modes: samples outside this HU range classify to zero opacity
uniform vec2 uTableSize;
uniform vec4 uClip;
uniform vec3 uHighlight;
uniform vec2 uLighting;     // alpha, beta of Eq. 6
uniform vec3 uSpacingMm;
uniform ivec3 uDims;
uniform int uBlock;         // voxels per occupancy block edge
uniform ivec3 uBlocks;
uniform int uJitter;
uniform int uSkip;
uniform vec4 uBackground;

float huAt(vec3 t) { return texture(uHu, t).r * 65535.0 - 32768.0; }
float fieldAt(vec3 f) { return texture(uField, f).r; }

// The selected structure's mask (1 inside), linearly filtered: the bare-mode surface is at 0.5.
float maskAt(vec3 t) { return texture(uMask, t).r; }

float normalisedDistance(float d) {
  return 2.0 / (1.0 + exp2(min(d * uLog2Alpha, 126.0)));
}

vec4 tableAt(float hu, float n) {
  float u = clamp((hu - uDataRange.x) / (uDataRange.y - uDataRange.x), 0.0, 1.0);
  vec2 uv = (vec2(u, clamp(n, 0.0, 1.0)) * (uTableSize - 1.0) + 0.5) / uTableSize;
  return texture(uTable, uv);
}

vec3 maskGradientAt(vec3 t) {
  vec3 d = 1.0 / vec3(uDims);
  vec3 g = vec3(maskAt(t + vec3(d.x, 0, 0)) - maskAt(t - vec3(d.x, 0, 0)),
                maskAt(t + vec3(0, d.y, 0)) - maskAt(t - vec3(0, d.y, 0)),
                maskAt(t + vec3(0, 0, d.z)) - maskAt(t - vec3(0, 0, d.z)));
  return g / (2.0 * uSpacingMm);
}

float hash(vec2 p) {
  return fract(sin(dot(p, vec2(12.9898, 78.233))) * 43758.5453);
}

vec4 castRay(vec2 pixel) {
  vec2 ndc = pixel / uViewport * 2.0 - 1.0;
  vec4 a = uInvViewProj * vec4(ndc, -1.0, 1.0);
  vec4 b = uInvViewProj * vec4(ndc, 1.0, 1.0);
  vec3 origin = a.xyz / a.w;
  vec3 dir = normalize(b.xyz / b.w - origin);
  vec3 oT = (uPatientToTex * vec4(origin, 1.0)).xyz;
  vec3 dT = (uPatientToTex * vec4(dir, 0.0)).xyz;
  // Slab test against the texture box [0,1]^3.
  vec3 inv = 1.0 / dT;
  vec3 ta = (vec3(0.0) - oT) * inv, tb = (vec3(1.0) - oT) * inv;
  vec3 tmin = min(ta, tb), tmax = max(ta, tb);
  float t0 = max(max(tmin.x, tmin.y), max(tmin.z, 0.0));
  float t1 = min(min(tmax.x, tmax.y), tmax.z);
  vec4 acc = vec4(0.0);
  if (t0 < t1) {
    vec3 oF = (uPatientToField * vec4(origin, 1.0)).xyz;
    vec3 dF = (uPatientToField * vec4(dir, 0.0)).xyz;
    float start = t0 + uStepMm * (uJitter != 0 ? hash(pixel) : 0.5);
    int count = int(ceil((t1 - start) / uStepMm));
    vec3 dims = vec3(uDims);
    float block = float(uBlock);
    bvec3 moving = notEqual(dT, vec3(0.0));
    vec3 light = -dir;
    int i = 0;
    ivec3 lastCell = ivec3(-1);
    bool occupied = true;
    // Samples before tBlockEnd lie in the occupied block the ray last entered: they skip the
    // block lookup. (A sample just past that block taken as inside it only costs its classification:
    // an empty block's samples all classify to zero opacity.)
    float tBlockEnd = -1e30;
    while (i < count) {
      float tm = start + float(i) * uStepMm;
      vec3 pt = oT + tm * dT;
      if (uSkip != 0 && tm >= tBlockEnd) {
        // Continuous voxel coordinates (centres at integers) and the block holding them; the
        // occupancy is fetched again only when the ray enters another block.
        ivec3 cell = clamp(ivec3(floor((pt * dims - 0.5) / block)), ivec3(0), uBlocks - 1);
        if (cell != lastCell) {
          lastCell = cell;
          occupied = texelFetch(uOccupancy, cell, 0).r != 0u;
        }
        // Where the ray leaves this block (the outermost blocks reach beyond the box, so a ray
        // leaving through them ends).
        vec3 lo = mix(vec3(cell * uBlock), vec3(-2.0), equal(cell, ivec3(0)));
        vec3 hi = mix(vec3((cell + 1) * uBlock), dims + 2.0, equal(cell, uBlocks - 1));
        vec3 bound = mix(lo, hi, greaterThan(dT, vec3(0.0)));
        vec3 te = mix(vec3(1e30), ((bound + 0.5) / dims - oT) * inv, moving);
        float tExit = min(te.x, min(te.y, te.z));
        if (!occupied) {
          // Jump to the first sample of the regular sequence past this block.
          i = max(i + 1, int(ceil((tExit - start) / uStepMm - 1e-3)));
          continue;
        }
        tBlockEnd = tExit;
      }
      ++i;
      vec3 p = origin + tm * dir;
      if (RAY_CLIP != 0 && dot(uClip.xyz, p) > uClip.w) continue;
      vec4 c;
      float d = 1e30;
      if (RAY_MODE == 1) {
        float m = maskAt(pt);
        if (m < 0.5) continue;
        c = vec4(uHighlight, uBareAlpha);
      } else {
        float hu = huAt(pt);
        // Transparent at every distance (no table column it filters from is visible): skip the
        // field and table reads.
        if (hu < uVisibleHu.x || hu > uVisibleHu.y) continue;
        float n = 0.0;
        if (uHasField != 0) {
          d = fieldAt(oF + tm * dF);
          n = normalisedDistance(d);
        }
        c = tableAt(hu, n);
      }
      float alpha = c.a;
      if (alpha <= 0.0) continue;
      vec3 rgb = c.rgb;
      // Shading: skip it where the sample cannot change a pixel's 8-bit value.
      if (RAY_SHADING != 0 && alpha * (1.0 - acc.a) > 1.0 / 1024.0) {
        vec3 nrm;
        float len;
        if (RAY_MODE == 1) {
          vec3 g = maskGradientAt(pt);
          len = length(g) > 1e-6 ? 1.0 : 0.0;
          nrm = len > 0.0 ? normalize(g) : vec3(0.0);
        } else {
          nrm = texture(uNormals, pt).xyz;  // interpolated unit normals: near unit length
          len = length(nrm);
          nrm = len > 1e-3 ? nrm / len : vec3(0.0);
        }
        float diffuse = 1.0, spec = 0.0;
        if (len > 1e-3) {
          float ndl = abs(dot(nrm, light));
          diffuse = ndl;
          float n2 = ndl * ndl, n4 = n2 * n2, n8 = n4 * n4;
          spec = n8 * n8 * n8;  // ndl^24 without pow's log/exp
        }
        if (RAY_MODE == 2) {
          float ka = uLighting.y / pow(uLighting.x * min(d, 1e6) + 1.0, 2.0);
          rgb = rgb * (ka * uHighlight + 0.2 * diffuse) + 0.1 * spec * ka;
        } else {
          rgb = rgb * (0.3 + 0.7 * diffuse) + 0.2 * spec;
        }
      } else if (RAY_MODE == 2) {
        float ka = uLighting.y / pow(uLighting.x * min(d, 1e6) + 1.0, 2.0);
        rgb = rgb * ka * uHighlight;
      }
      acc.rgb += (1.0 - acc.a) * alpha * clamp(rgb, 0.0, 1.0);
      acc.a += (1.0 - acc.a) * alpha;
      if (acc.a > 0.995) break;
    }
  }
  float bgA = uBackground.a * (1.0 - acc.a);
  float outA = acc.a + bgA;
  vec3 premul = acc.rgb + bgA * uBackground.rgb;
  return vec4(outA > 0.0 ? premul / outA : vec3(0.0), outA);
}
)";

const char* kFragmentMain = R"(#version 430 core
out vec4 fragColor;
vec4 castRay(vec2 pixel);
void main() { fragColor = castRay(gl_FragCoord.xy); }
)";

// The same rays from a compute shader, one invocation per pixel into the colour image.
const char* kComputeMain = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba8, binding = 0) writeonly uniform image2D uImage;
uniform vec2 uViewport;
vec4 castRay(vec2 pixel);
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, ivec2(uViewport)))) return;
  imageStore(uImage, p, castRay(vec2(p) + 0.5));
}
)";

// Unit gradient directions of HU at voxel centres (central differences in mm, edge-clamped as the
// old per-sample gradient was), zero where the gradient vanishes. Run once per volume.
const char* kNormalShader = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8, local_size_z = 4) in;
layout(binding = 0) uniform sampler3D uHu;
layout(rgba8_snorm, binding = 1) writeonly uniform image3D uNormalsOut;
uniform ivec3 uDims;
uniform vec3 uSpacingMm;
float hu(ivec3 p) { return texelFetch(uHu, clamp(p, ivec3(0), uDims - 1), 0).r * 65535.0; }
void main() {
  ivec3 p = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(p, uDims))) return;
  vec3 g = vec3(hu(p + ivec3(1, 0, 0)) - hu(p - ivec3(1, 0, 0)),
                hu(p + ivec3(0, 1, 0)) - hu(p - ivec3(0, 1, 0)),
                hu(p + ivec3(0, 0, 1)) - hu(p - ivec3(0, 0, 1))) / (2.0 * uSpacingMm);
  float len = length(g);
  imageStore(uNormalsOut, p, vec4(len > 1e-6 ? g / len : vec3(0.0), 0.0));
}
)";

// Builds the selected structure's mask (R8: 1 where label == selected) from the label texture.
const char* kMaskShader = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8, local_size_z = 4) in;
layout(binding = 0) uniform usampler3D uLabels;
layout(r8, binding = 1) writeonly uniform image3D uMaskOut;
uniform uint uSelected;
uniform ivec3 uDims;
void main() {
  ivec3 p = ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(p, uDims))) return;
  uint l = texelFetch(uLabels, p, 0).r;
  imageStore(uMaskOut, p, vec4(l == uSelected && uSelected != 0u ? 1.0 : 0.0));
}
)";

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

Result<Program> linkCompute(const char* source, const char* what) {
  auto cs = compile<ComputeShader>(source, what);
  if (!cs) return tl::unexpected(cs.error());
  return link({cs->id()}, what);
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

// Distances as the field texture holds them: +infinity (unreachable) is stored as 1e30, which the
// shader's normalisation treats as far.
void copyFinite(const float* src, std::size_t count, float* dst) {
  for (std::size_t i = 0; i < count; ++i) dst[i] = std::isfinite(src[i]) ? src[i] : 1e30f;
}

void setTextureParams(GLenum filter) {
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GLint(filter));
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GLint(filter));
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_3D, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

// Edge of the blocks of the occupancy grid, in voxels.
constexpr int kBlockVoxels = 8;

// What the occupancy grid is built from, per block of kBlockVoxels³ voxels, computed once per
// volume. A sample in block b interpolates voxels of b and the first voxel beyond it, so the HU
// range covers the 27 neighbouring blocks (any interpolated value lies inside it); the labels are
// those of the block itself (bare-mode occupancy looks at the neighbours).
struct BlockSummary {
  Dims blocks;
  std::vector<std::int16_t> huMin, huMax;
  std::vector<std::vector<std::uint16_t>> labels;  // sorted

  std::size_t index(int i, int j, int k) const { return blocks.index(i, j, k); }
};

BlockSummary summariseBlocks(const Volume& volume, const LabelMap& labels) {
  const Dims& d = volume.dims();
  BlockSummary b;
  b.blocks = {(d.x + kBlockVoxels - 1) / kBlockVoxels, (d.y + kBlockVoxels - 1) / kBlockVoxels,
              (d.z + kBlockVoxels - 1) / kBlockVoxels};
  const std::size_t n = b.blocks.count();
  std::vector<std::int16_t> ownMin(n, std::numeric_limits<std::int16_t>::max());
  std::vector<std::int16_t> ownMax(n, std::numeric_limits<std::int16_t>::min());
  b.labels.assign(n, {});
  const bool hasLabels = !labels.empty();
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j) {
      const std::size_t row = d.index(0, j, k);
      const std::size_t blockRow = b.index(0, j / kBlockVoxels, k / kBlockVoxels);
      std::size_t lastBlock = n;
      std::uint16_t lastLabel = 0;
      for (int i = 0; i < d.x; ++i) {
        const std::size_t bi = blockRow + std::size_t(i / kBlockVoxels);
        const std::int16_t v = volume.voxels[row + std::size_t(i)];
        ownMin[bi] = std::min(ownMin[bi], v);
        ownMax[bi] = std::max(ownMax[bi], v);
        if (!hasLabels) continue;
        const std::uint16_t l = labels.voxels[row + std::size_t(i)];
        if (l == 0 || (bi == lastBlock && l == lastLabel)) continue;
        lastBlock = bi;
        lastLabel = l;
        auto& set = b.labels[bi];
        const auto at = std::lower_bound(set.begin(), set.end(), l);
        if (at == set.end() || *at != l) set.insert(at, l);
      }
    }
  b.huMin.resize(n);
  b.huMax.resize(n);
  const Dims& nb = b.blocks;
  for (int k = 0; k < nb.z; ++k)
    for (int j = 0; j < nb.y; ++j)
      for (int i = 0; i < nb.x; ++i) {
        std::int16_t lo = std::numeric_limits<std::int16_t>::max(), hi = std::numeric_limits<std::int16_t>::min();
        for (int dk = std::max(k - 1, 0); dk <= std::min(k + 1, nb.z - 1); ++dk)
          for (int dj = std::max(j - 1, 0); dj <= std::min(j + 1, nb.y - 1); ++dj)
            for (int di = std::max(i - 1, 0); di <= std::min(i + 1, nb.x - 1); ++di) {
              lo = std::min(lo, ownMin[b.index(di, dj, dk)]);
              hi = std::max(hi, ownMax[b.index(di, dj, dk)]);
            }
        b.huMin[b.index(i, j, k)] = lo;
        b.huMax[b.index(i, j, k)] = hi;
      }
  return b;
}

// Occupancy for the table modes: a block may hold a visible sample when some table column its HU
// range reaches (with the linear filter's neighbour) has a non-zero opacity at any distance.
std::vector<std::uint8_t> tableOccupancy(const BlockSummary& b, const TransferFunction2D& table,
                                         const std::vector<float>& columnMaxAlpha) {
  std::vector<std::uint8_t> occ(b.blocks.count(), 0);
  // Prefix counts of visible columns: "any visible column in [c0, c1]" in O(1).
  std::vector<int> visibleBefore(columnMaxAlpha.size() + 1, 0);
  for (std::size_t c = 0; c < columnMaxAlpha.size(); ++c)
    visibleBefore[c + 1] = visibleBefore[c] + (columnMaxAlpha[c] > 0.0f ? 1 : 0);
  const double last = double(table.dataSize - 1);
  const auto column = [&](double hu) {
    return std::clamp((hu - table.dataMin) / (table.dataMax - table.dataMin), 0.0, 1.0) * last;
  };
  for (std::size_t i = 0; i < occ.size(); ++i) {
    if (b.huMin[i] > b.huMax[i]) continue;
    const int c0 = std::max(0, int(std::floor(column(b.huMin[i]))));
    const int c1 = std::min(table.dataSize - 1, int(std::ceil(column(b.huMax[i]))));
    occ[i] = visibleBefore[std::size_t(c1) + 1] - visibleBefore[std::size_t(c0)] > 0 ? 1 : 0;
  }
  return occ;
}

// The HU range outside which a table lookup is zero at every distance: the linear filter reads
// columns floor(c) and floor(c) + 1 at column coordinate c = (hu − dataMin) / span · (size − 1),
// so a sample at or before the centre of the column preceding the first visible one (or at or
// after the centre of the one following the last) reads only invisible columns. A hundredth of a
// column of margin keeps the test on the safe side of float rounding. Empty range: nothing visible.
std::array<float, 2> visibleHuRange(const TransferFunction2D& table, const std::vector<float>& columnMaxAlpha) {
  int first = -1, last = -1;
  for (int c = 0; c < int(columnMaxAlpha.size()); ++c) {
    if (columnMaxAlpha[std::size_t(c)] > 0.0f) {
      if (first < 0) first = c;
      last = c;
    }
  }
  constexpr float kFar = 1e30f;
  if (first < 0) return {kFar, -kFar};
  const double perColumn = (table.dataMax - table.dataMin) / double(table.dataSize - 1);
  const float lo = first == 0 ? -kFar : float(table.dataMin + (first - 1 - 0.01) * perColumn);
  const float hi = last == table.dataSize - 1 ? kFar : float(table.dataMin + (last + 1 + 0.01) * perColumn);
  return {lo, hi};
}

// Occupancy for bare mode: a block may hold mask ≥ 0.5 when it or a neighbour holds the label.
std::vector<std::uint8_t> labelOccupancy(const BlockSummary& b, std::uint16_t label) {
  std::vector<std::uint8_t> own(b.blocks.count(), 0), occ(b.blocks.count(), 0);
  if (label == 0) return occ;
  for (std::size_t i = 0; i < own.size(); ++i)
    own[i] = std::binary_search(b.labels[i].begin(), b.labels[i].end(), label) ? 1 : 0;
  const Dims& nb = b.blocks;
  for (int k = 0; k < nb.z; ++k)
    for (int j = 0; j < nb.y; ++j)
      for (int i = 0; i < nb.x; ++i) {
        std::uint8_t any = 0;
        for (int dk = std::max(k - 1, 0); dk <= std::min(k + 1, nb.z - 1) && !any; ++dk)
          for (int dj = std::max(j - 1, 0); dj <= std::min(j + 1, nb.y - 1) && !any; ++dj)
            for (int di = std::max(i - 1, 0); di <= std::min(i + 1, nb.x - 1) && !any; ++di)
              any = own[b.index(di, dj, dk)];
        occ[b.index(i, j, k)] = any;
      }
  return occ;
}

Status glStatus(const char* what) {
  const GLenum e = glGetError();
  if (e == GL_NO_ERROR) return {};
  if (e == GL_OUT_OF_MEMORY) return fail(std::string("GL: out of GPU memory during ") + what);
  return fail(std::string("GL: error 0x") + [&] {
    char buf[16];
    std::snprintf(buf, sizeof buf, "%04x", unsigned(e));
    return std::string(buf);
  }() + " during " + what);
}

// What the ray caster's program is specialised to: the render mode and whether shading and a
// clipping plane are on are compile-time constants of the shader (RAY_MODE, RAY_SHADING,
// RAY_CLIP), so their per-sample branches and the unused modes' code (the bare mode's six-fetch
// mask gradient) leave the program. Measured on an H100 at 1920×1080, 512³: 8.78 ms a frame with
// uniforms, 8.43 with the mode specialised, 8.40 with all three (bench/RESULTS.md).
struct RayVariant {
  static constexpr int kCount = 12;
  int mode = 0;  // 0 table, 1 bare, 2 lighting
  bool shading = true, clip = false;
  int index() const { return mode + 3 * (shading ? 1 : 0) + 6 * (clip ? 1 : 0); }
  std::string defines() const {
    return "#define RAY_MODE " + std::to_string(mode) + "\n#define RAY_SHADING " + (shading ? "1" : "0") +
           "\n#define RAY_CLIP " + (clip ? "1" : "0") + "\n";
  }
};

// The ray caster program of one variant, compiled and linked on first use, then kept.
Result<GLuint> rayCasterProgram(std::array<Program, RayVariant::kCount>& fragmentRayCasters,
                                std::array<Program, RayVariant::kCount>& computeRayCasters, RayCaster kind,
                                RayVariant variant) {
  Program& slot = kind == RayCaster::Compute ? computeRayCasters[std::size_t(variant.index())]
                                             : fragmentRayCasters[std::size_t(variant.index())];
  if (slot) return slot.id();
  const std::string source = "#version 430 core\n" + variant.defines() + kRayCaster;
  if (kind == RayCaster::Compute) {
    auto main = compile<ComputeShader>(kComputeMain, "compute");
    if (!main) return tl::unexpected(main.error());
    auto ray = compile<ComputeShader>(source.c_str(), "compute ray caster");
    if (!ray) return tl::unexpected(ray.error());
    auto linked = link({main->id(), ray->id()}, "compute ray caster");
    if (!linked) return tl::unexpected(linked.error());
    slot = std::move(*linked);
  } else {
    auto vs = compile<VertexShader>(kVertexShader, "vertex");
    if (!vs) return tl::unexpected(vs.error());
    auto main = compile<FragmentShader>(kFragmentMain, "fragment");
    if (!main) return tl::unexpected(main.error());
    auto ray = compile<FragmentShader>(source.c_str(), "fragment ray caster");
    if (!ray) return tl::unexpected(ray.error());
    auto linked = link({vs->id(), main->id(), ray->id()}, "fragment ray caster");
    if (!linked) return tl::unexpected(linked.error());
    slot = std::move(*linked);
  }
  return slot.id();
}

}  // namespace

struct VolumeRenderer::State {
  // The ray casters, one per RayVariant, compiled on first use: fragment and compute entry points.
  std::array<Program, RayVariant::kCount> fragmentRayCasters, computeRayCasters;
  Program maskProgram, normalProgram;
  VertexArray vao;
  Texture hu, labels, field, table, mask, normals, occupancy;
  // uploadFieldStep: the texture being filled, what it is filled from and the next z-slice.
  Texture pendingField;
  Dims pendingDims;   // of pendingField's storage (zero: none)
  Dims fieldDims;     // of field's storage
  const float* pendingSource = nullptr;
  Geometry pendingGrid;
  int pendingNextSlice = 0;
  int maskLabel = -1;  // label the mask texture holds; -1 = stale
  std::optional<Preset> tablePreset;  // the preset the table texture was built from …
  double tableStepMm = 0, tableRefMm = 0;  // … and the step its opacities are corrected to
  TransferFunction2D tableInfo;       // its axes (rgba dropped after upload)
  std::vector<float> columnMaxAlpha;  // per table column: the largest corrected opacity
  BlockSummary blocks;
  int occupancyFor = kOccupancyStale;  // kOccupancyTable, a bare-mode label, or stale
  Framebuffer fbo;
  Texture colour;  // RGBA8, the framebuffer's attachment and the compute path's image
  RayCaster rayCaster = RayCaster::Compute;
  Query timer;
  int fboWidth = 0, fboHeight = 0;
  Geometry volumeGrid, fieldGrid;
  bool hasVolume = false, hasField = false;
#if defined(AT_HAVE_CUDA)
  std::optional<cuda::GlTextureTarget> interop;  // registered field texture storage
  Dims interopDims;
#endif
};

VolumeRenderer::VolumeRenderer(std::unique_ptr<State> s) : state_(std::move(s)) {}
VolumeRenderer::~VolumeRenderer() = default;
VolumeRenderer::VolumeRenderer(VolumeRenderer&&) noexcept = default;
VolumeRenderer& VolumeRenderer::operator=(VolumeRenderer&&) noexcept = default;

Result<VolumeRenderer> VolumeRenderer::create() {
  auto s = std::make_unique<State>();
  // Compile the default mode's ray casters now, so that a driver that rejects the shader fails
  // here, with its message, rather than at the first frame.
  for (RayCaster kind : {RayCaster::Compute, RayCaster::Fragment}) {
    if (auto p = rayCasterProgram(s->fragmentRayCasters, s->computeRayCasters, kind, RayVariant{}); !p)
      return tl::unexpected(p.error());
  }
  auto mask = linkCompute(kMaskShader, "mask");
  if (!mask) return tl::unexpected(mask.error());
  s->maskProgram = std::move(*mask);
  auto normals = linkCompute(kNormalShader, "normal");
  if (!normals) return tl::unexpected(normals.error());
  s->normalProgram = std::move(*normals);
  s->vao = VertexArray::make();
  s->hu = Texture::make();
  s->labels = Texture::make();
  s->field = Texture::make();
  s->table = Texture::make();
  s->fbo = Framebuffer::make();
  s->timer = Query::make();
  if (auto st = glStatus("creating the ray caster"); !st) return tl::unexpected(st.error());
  return VolumeRenderer(std::move(s));
}

Status VolumeRenderer::setVolume(const Volume& volume, const LabelMap& labels) {
  if (volume.empty()) return fail("render: the volume is empty");
  if (!labels.empty() && !(labels.dims() == volume.dims()))
    return fail("render: labels " + labels.dims().toString() + " are not on the volume's grid " +
                volume.dims().toString());
  const Dims& d = volume.dims();
  // A field upload in progress, and its spare texture, belong to the previous volume.
  state_->pendingField = Texture();
  state_->pendingDims = Dims{};
  state_->pendingSource = nullptr;
  state_->pendingGrid = Geometry{};
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  std::vector<std::uint16_t> shifted(volume.voxels.size());
  for (std::size_t i = 0; i < shifted.size(); ++i) shifted[i] = std::uint16_t(int(volume.voxels[i]) + 32768);
  glBindTexture(GL_TEXTURE_3D, state_->hu.id());
  setTextureParams(GL_LINEAR);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R16, d.x, d.y, d.z, 0, GL_RED, GL_UNSIGNED_SHORT, shifted.data());
  shifted.clear();
  shifted.shrink_to_fit();
  glBindTexture(GL_TEXTURE_3D, state_->labels.id());
  setTextureParams(GL_NEAREST);
  if (labels.empty()) {
    std::vector<std::uint16_t> zeros(volume.voxels.size(), 0);
    glTexImage3D(GL_TEXTURE_3D, 0, GL_R16UI, d.x, d.y, d.z, 0, GL_RED_INTEGER, GL_UNSIGNED_SHORT, zeros.data());
  } else {
    glTexImage3D(GL_TEXTURE_3D, 0, GL_R16UI, d.x, d.y, d.z, 0, GL_RED_INTEGER, GL_UNSIGNED_SHORT, labels.voxels.data());
  }
  // The mask texture needs immutable storage to be written as an image.
  state_->mask = Texture::make();
  glBindTexture(GL_TEXTURE_3D, state_->mask.id());
  glTexStorage3D(GL_TEXTURE_3D, 1, GL_R8, d.x, d.y, d.z);
  setTextureParams(GL_LINEAR);
  state_->maskLabel = -1;
  // Normals for shading, once per volume.
  state_->normals = Texture::make();
  glBindTexture(GL_TEXTURE_3D, state_->normals.id());
  glTexStorage3D(GL_TEXTURE_3D, 1, GL_RGBA8_SNORM, d.x, d.y, d.z);
  setTextureParams(GL_LINEAR);
  glUseProgram(state_->normalProgram.id());
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_3D, state_->hu.id());
  glUniform1i(glGetUniformLocation(state_->normalProgram.id(), "uHu"), 0);
  glBindImageTexture(1, state_->normals.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA8_SNORM);
  glUniform3i(glGetUniformLocation(state_->normalProgram.id(), "uDims"), d.x, d.y, d.z);
  glUniform3f(glGetUniformLocation(state_->normalProgram.id(), "uSpacingMm"), float(volume.geometry.spacingMm[0]),
              float(volume.geometry.spacingMm[1]), float(volume.geometry.spacingMm[2]));
  glDispatchCompute(GLuint((d.x + 7) / 8), GLuint((d.y + 7) / 8), GLuint((d.z + 3) / 4));
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
  // Block summaries for empty-space skipping; the occupancy grid follows the table or label.
  state_->blocks = summariseBlocks(volume, labels);
  const Dims& nb = state_->blocks.blocks;
  state_->occupancy = Texture::make();
  glBindTexture(GL_TEXTURE_3D, state_->occupancy.id());
  glTexStorage3D(GL_TEXTURE_3D, 1, GL_R8UI, nb.x, nb.y, nb.z);
  setTextureParams(GL_NEAREST);
  state_->occupancyFor = kOccupancyStale;
  state_->volumeGrid = volume.geometry;
  state_->hasVolume = true;
  state_->hasField = false;
  return glStatus("uploading the volume");
}

bool VolumeRenderer::hasCudaInterop() {
#if defined(AT_HAVE_CUDA)
  return true;
#else
  return false;
#endif
}

Status VolumeRenderer::setFieldFromDevice(const cuda::DeviceField& field) {
#if defined(AT_HAVE_CUDA)
  State& st = *state_;
  const Geometry& grid = field.grid();
  if (!st.interop || !(st.interopDims == grid.dims)) {
    // New storage: allocate the texture and register it with CUDA once for this size.
    st.interop.reset();
    glBindTexture(GL_TEXTURE_3D, st.field.id());
    setTextureParams(GL_LINEAR);
    glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, grid.dims.x, grid.dims.y, grid.dims.z, 0, GL_RED, GL_FLOAT, nullptr);
    st.fieldDims = grid.dims;
    if (auto s = glStatus("allocating the distance field"); !s) return s;
    auto target = cuda::GlTextureTarget::registerTexture(st.field.id(), grid.dims.x, grid.dims.y, grid.dims.z);
    if (!target) return tl::unexpected(target.error());
    st.interop.emplace(std::move(*target));
    st.interopDims = grid.dims;
  }
  if (auto s = st.interop->copyFrom(field); !s) return s;
  st.fieldGrid = grid;
  st.hasField = true;
  return {};
#else
  (void)field;
  return fail(ErrorKind::Unavailable, "render: this build has no CUDA, so a device field cannot be shown");
#endif
}

Status VolumeRenderer::setField(const FloatVolume& field) {
  if (field.empty()) return fail("render: the distance field is empty");
  std::vector<float> finite(field.voxels.size());
  copyFinite(field.voxels.data(), finite.size(), finite.data());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_3D, state_->field.id());
  setTextureParams(GL_LINEAR);
  const Dims& d = field.dims();
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, d.x, d.y, d.z, 0, GL_RED, GL_FLOAT, finite.data());
  state_->fieldDims = d;
#if defined(AT_HAVE_CUDA)
  state_->interop.reset();  // the storage changed: a registration would be stale
#endif
  state_->fieldGrid = field.geometry;
  state_->hasField = true;
  return glStatus("uploading the distance field");
}

Result<bool> VolumeRenderer::uploadFieldStep(const FloatVolume& field, double budgetMs) {
  if (field.empty()) return fail("render: the distance field is empty");
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
    if (!st.pendingField || !(st.pendingDims == d)) {
      st.pendingField = Texture::make();
      glBindTexture(GL_TEXTURE_3D, st.pendingField.id());
      setTextureParams(GL_LINEAR);
      // Mutable storage, as setField's: the texture becomes the field texture, which setField and
      // setFieldFromDevice re-specify.
      glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, d.x, d.y, d.z, 0, GL_RED, GL_FLOAT, nullptr);
      if (auto e = glStatus("allocating the distance field"); !e) return tl::unexpected(e.error());
      st.pendingDims = d;
      return false;
    }
  }
  const auto start = std::chrono::steady_clock::now();
  const std::size_t slice = std::size_t(d.x) * std::size_t(d.y);
  std::vector<float> finite(slice);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glBindTexture(GL_TEXTURE_3D, st.pendingField.id());
  do {
    const float* src = field.voxels.data() + slice * std::size_t(st.pendingNextSlice);
    copyFinite(src, slice, finite.data());
    glTexSubImage3D(GL_TEXTURE_3D, 0, 0, 0, st.pendingNextSlice, d.x, d.y, 1, GL_RED, GL_FLOAT, finite.data());
    ++st.pendingNextSlice;
  } while (st.pendingNextSlice < d.z &&
           std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() < budgetMs);
  if (auto e = glStatus("uploading the distance field"); !e) return tl::unexpected(e.error());
  if (st.pendingNextSlice < d.z) return false;
  // The filled texture becomes the field; the previous field texture is the spare for the next.
  std::swap(st.field, st.pendingField);
  std::swap(st.fieldDims, st.pendingDims);
  st.pendingSource = nullptr;
  st.pendingGrid = Geometry{};
#if defined(AT_HAVE_CUDA)
  st.interop.reset();  // the storage changed: a registration would be stale
#endif
  st.fieldGrid = field.geometry;
  st.hasField = true;
  return true;
}

void VolumeRenderer::clearField() { state_->hasField = false; }

void VolumeRenderer::setRayCaster(RayCaster r) { state_->rayCaster = r; }

Status VolumeRenderer::draw(const RenderSettings& s) {
  if (!state_->hasVolume) return fail("render: no volume uploaded");
  if (s.width <= 0 || s.height <= 0 || s.width > 16384 || s.height > 16384)
    return fail("render: image size " + std::to_string(s.width) + "x" + std::to_string(s.height) + " is out of range");
  State& st = *state_;
  if (st.fboWidth != s.width || st.fboHeight != s.height) {
    st.colour = Texture::make();
    glBindTexture(GL_TEXTURE_2D, st.colour.id());
    glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA8, s.width, s.height);
    glBindFramebuffer(GL_FRAMEBUFFER, st.fbo.id());
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, st.colour.id(), 0);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      return fail("render: the offscreen framebuffer is incomplete");
    st.fboWidth = s.width;
    st.fboHeight = s.height;
  }
  if (s.preset.mode == RenderMode::Bare && st.maskLabel != int(selected_)) {
    const Dims& d = st.volumeGrid.dims;
    glUseProgram(st.maskProgram.id());
    glActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_3D, st.labels.id());
    glUniform1i(glGetUniformLocation(st.maskProgram.id(), "uLabels"), 0);
    glBindImageTexture(1, st.mask.id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R8);
    glUniform1ui(glGetUniformLocation(st.maskProgram.id(), "uSelected"), selected_);
    glUniform3i(glGetUniformLocation(st.maskProgram.id(), "uDims"), d.x, d.y, d.z);
    glDispatchCompute(GLuint((d.x + 7) / 8), GLuint((d.y + 7) / 8), GLuint((d.z + 3) / 4));
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    st.maskLabel = int(selected_);
    if (auto e = glStatus("building the structure mask"); !e) return e;
  }
  // The 2-D table of the mode, its opacities corrected to the step.
  const double stepMm = effectiveStepMm(st.volumeGrid, s);
  if (!st.tablePreset || !(*st.tablePreset == s.preset) || st.tableStepMm != stepMm ||
      st.tableRefMm != s.opacityRefMm) {
    TransferFunction2D table = shadingTable(s.preset);
    st.columnMaxAlpha.assign(std::size_t(table.dataSize), 0.0f);
    for (int j = 0; j < table.distanceSize; ++j)
      for (int i = 0; i < table.dataSize; ++i) {
        Rgba& v = table.rgba[std::size_t(i) + std::size_t(table.dataSize) * std::size_t(j)];
        v[3] = v[3] > 0.0f ? correctedOpacity(v[3], stepMm, s.opacityRefMm) : 0.0f;
        st.columnMaxAlpha[std::size_t(i)] = std::max(st.columnMaxAlpha[std::size_t(i)], v[3]);
      }
    glBindTexture(GL_TEXTURE_2D, st.table.id());
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F, table.dataSize, table.distanceSize, 0, GL_RGBA, GL_FLOAT,
                 table.rgba.data());
    table.rgba.clear();
    st.tableInfo = std::move(table);
    st.tablePreset = s.preset;
    st.tableStepMm = stepMm;
    st.tableRefMm = s.opacityRefMm;
    if (st.occupancyFor == kOccupancyTable) st.occupancyFor = kOccupancyStale;
  }
  const TransferFunction2D& table = st.tableInfo;
  // Which blocks rays may skip.
  const int occupancyFor = s.preset.mode == RenderMode::Bare ? int(selected_) : kOccupancyTable;
  if (st.occupancyFor != occupancyFor) {
    const std::vector<std::uint8_t> occ = occupancyFor == kOccupancyTable
                                              ? tableOccupancy(st.blocks, table, st.columnMaxAlpha)
                                              : labelOccupancy(st.blocks, selected_);
    const Dims& nb = st.blocks.blocks;
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glBindTexture(GL_TEXTURE_3D, st.occupancy.id());
    glTexSubImage3D(GL_TEXTURE_3D, 0, 0, 0, 0, nb.x, nb.y, nb.z, GL_RED_INTEGER, GL_UNSIGNED_BYTE, occ.data());
    st.occupancyFor = occupancyFor;
    if (auto e = glStatus("uploading the occupancy grid"); !e) return e;
  }

  glBindFramebuffer(GL_FRAMEBUFFER, st.fbo.id());
  glViewport(0, 0, s.width, s.height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  const bool compute = st.rayCaster == RayCaster::Compute;
  const RenderMode mode = s.preset.mode;
  RayVariant variant;
  variant.mode = mode == RenderMode::Bare ? 1 : (mode == RenderMode::Lighting ? 2 : 0);
  variant.shading = s.shading;
  variant.clip = s.clip.has_value();
  auto program = rayCasterProgram(st.fragmentRayCasters, st.computeRayCasters, st.rayCaster, variant);
  if (!program) return tl::unexpected(program.error());
  const GLuint p = *program;
  glUseProgram(p);
  const auto loc = [p](const char* n) { return glGetUniformLocation(p, n); };
  const auto setMat = [&](const char* n, const Mat4& m) {
    const auto f = m.toFloat();
    glUniformMatrix4fv(loc(n), 1, GL_FALSE, f.data());
  };
  setMat("uInvViewProj", s.camera.viewProjection(double(s.width) / double(s.height)).inverse());
  setMat("uPatientToTex", patientToTexture(st.volumeGrid));
  setMat("uPatientToField", patientToTexture(st.hasField ? st.fieldGrid : st.volumeGrid));
  glUniform2f(loc("uViewport"), float(s.width), float(s.height));
  glUniform1i(loc("uHasField"), st.hasField ? 1 : 0);
  glUniform1f(loc("uStepMm"), float(stepMm));
  glUniform1f(loc("uBareAlpha"), correctedOpacity(1.0f, stepMm, s.opacityRefMm));
  glUniform1f(loc("uLog2Alpha"), std::log2(s.preset.alpha));
  glUniform2f(loc("uDataRange"), float(table.dataMin), float(table.dataMax));
  const std::array<float, 2> visibleHu = visibleHuRange(table, st.columnMaxAlpha);
  glUniform2f(loc("uVisibleHu"), visibleHu[0], visibleHu[1]);
  glUniform2f(loc("uTableSize"), float(table.dataSize), float(table.distanceSize));
  if (s.clip)
    glUniform4f(loc("uClip"), float(s.clip->normal[0]), float(s.clip->normal[1]), float(s.clip->normal[2]),
                float(s.clip->d));
  glUniform3f(loc("uHighlight"), s.preset.highlightRgb[0], s.preset.highlightRgb[1], s.preset.highlightRgb[2]);
  glUniform2f(loc("uLighting"), s.preset.lightingAlpha, s.preset.lightingBeta);
  glUniform3f(loc("uSpacingMm"), float(st.volumeGrid.spacingMm[0]), float(st.volumeGrid.spacingMm[1]),
              float(st.volumeGrid.spacingMm[2]));
  glUniform3i(loc("uDims"), st.volumeGrid.dims.x, st.volumeGrid.dims.y, st.volumeGrid.dims.z);
  glUniform1i(loc("uBlock"), kBlockVoxels);
  glUniform3i(loc("uBlocks"), st.blocks.blocks.x, st.blocks.blocks.y, st.blocks.blocks.z);
  glUniform1i(loc("uJitter"), s.jitter ? 1 : 0);
  glUniform1i(loc("uSkip"), s.skipEmptySpace ? 1 : 0);
  glUniform4f(loc("uBackground"), s.background[0], s.background[1], s.background[2], s.background[3]);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_3D, st.hu.id());
  glUniform1i(loc("uHu"), 0);
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_3D, st.mask.id());
  glUniform1i(loc("uMask"), 1);
  glActiveTexture(GL_TEXTURE2);
  glBindTexture(GL_TEXTURE_3D, st.field.id());
  glUniform1i(loc("uField"), 2);
  glActiveTexture(GL_TEXTURE3);
  glBindTexture(GL_TEXTURE_2D, st.table.id());
  glUniform1i(loc("uTable"), 3);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_3D, st.normals.id());
  glUniform1i(loc("uNormals"), 4);
  glActiveTexture(GL_TEXTURE5);
  glBindTexture(GL_TEXTURE_3D, st.occupancy.id());
  glUniform1i(loc("uOccupancy"), 5);
  glActiveTexture(GL_TEXTURE0);
  if (compute) {
    glBindImageTexture(0, st.colour.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA8);
    glUniform1i(loc("uImage"), 0);
    glDispatchCompute(GLuint((s.width + 7) / 8), GLuint((s.height + 7) / 8), 1);
    glMemoryBarrier(GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT);
  } else {
    glBindVertexArray(st.vao.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  return glStatus("drawing");
}

Result<RgbaImage> VolumeRenderer::render(const RenderSettings& s) {
  if (auto st = draw(s); !st) return tl::unexpected(st.error());
  RgbaImage image(s.width, s.height);
  std::vector<std::uint8_t> rows(image.rgba.size());
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
  const Status st = draw(s);
  glEndQuery(GL_TIME_ELAPSED);
  if (!st) return tl::unexpected(st.error());
  GLuint64 ns = 0;
  glGetQueryObjectui64v(state_->timer.id(), GL_QUERY_RESULT, &ns);
  return double(ns) * 1e-6;
}

}  // namespace at::render::gl
