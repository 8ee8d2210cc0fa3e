#include "ray_shaders.h"

namespace at::render::gl::shaders {

const char* const kFullScreenVertex = R"(#version 430 core
void main() {
  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);
}
)";

// Classification and shading as render_settings.h documents; keep in step with pick().
//
// Per sample, in this order (cheapest rejections first):
//  1. Empty-space skipping: the occupancy texel of the sample's block says whether the context
//     may draw there (bit 1) and whether the selected structure's mask reaches it (bit 2); a block
//     with neither is jumped over.
//  2. The selected structure (RAY_STRUCTURE): its smoothed mask's 0.5 level set is a surface.
//     Where the ray enters it, one surface sample is composited in the highlight colour with the
//     structure's opacity, lit by the mask's gradient; its inside draws nothing else, and the
//     context within about a voxel of it (mask > uMaskHalo) is left out so the bone wall that
//     coincides with its boundary does not veil it. (The paper's Algorithm 1 draws the structure
//     through the data TF at distance 0; a fluid- or air-filled structure then has the opacity of
//     fluid or air, and only the mask gives it the high opacity its figures show.)
//  3. The context (table modes): HU outside the visible range draw nothing; then the edge strength
//     from the gradient texture scales the table's opacity by the surface ramp (homogeneous
//     regions do not accumulate into fog, edges become surfaces); then the distance field and the
//     2-D table (opacities already corrected to the step), lit by the same gradient's direction.
// Rays start at a per-pixel jittered offset and stop at 0.98 accumulated opacity.
const char* const kRayCaster = R"(
uniform mat4 uInvViewProj;
uniform mat4 uPatientToTex;
uniform mat4 uPatientToField;
uniform vec2 uViewport;
uniform sampler3D uVolume;     // HU / 32767 and the gradient in HU per voxel / max (RGBA16 snorm)
uniform sampler3D uMask;
uniform sampler3D uField;
uniform usampler3D uOccupancy;  // bit 1: context may draw, bit 2: near the structure
uniform sampler2D uTable;       // RGBA, alpha corrected to the step
uniform int uHasField;
uniform float uStepMm;
uniform float uStructureAlpha;  // the structure surface's opacity (one sample, not per step)
uniform float uMaskHalo;
uniform float uFrontFactor;     // context opacity factor in front of the structure
uniform vec3 uMaskBoxLo;        // the structure's box, texture coordinates
uniform vec3 uMaskBoxHi;
uniform float uDistanceScale;   // log2(alpha) / distance unit
uniform float uDistanceOffset;  // subtracted from D (clamped at 0) before the unit
uniform float uBandN;           // outline: the band's n (render_settings.h, outlineBandN); < 0: none
uniform vec2 uDataRange;
uniform vec2 uVisibleHu;
uniform vec2 uTableSize;
uniform vec3 uSurface;          // edge strength ramp lo, hi (HU per voxel), interior opacity factor
uniform float uMaxStrength;
uniform vec4 uClip;
uniform vec3 uHighlight;
uniform vec2 uLighting;         // alpha / distance unit, beta of Eq. 6
uniform vec3 uLightDir;         // towards the key light, patient frame
uniform vec3 uDims;
uniform int uBlock;
uniform ivec3 uBlocks;
uniform int uJitter;
uniform int uSkip;
uniform vec4 uBackground;

float maskAt(vec3 t) { return texture(uMask, t).r; }

float normalisedDistance(float d) {
  return 2.0 / (1.0 + exp2(min(max(d - uDistanceOffset, 0.0) * uDistanceScale, 126.0)));
}

vec4 tableAt(float hu, float n) {
  float u = clamp((hu - uDataRange.x) / (uDataRange.y - uDataRange.x), 0.0, 1.0);
  vec2 uv = (vec2(u, clamp(n, 0.0, 1.0)) * (uTableSize - 1.0) + 0.5) / uTableSize;
  return texture(uTable, uv);
}

vec3 maskNormal(vec3 t) {
  vec3 d = 1.0 / uDims;
  vec3 g = vec3(maskAt(t + vec3(d.x, 0, 0)) - maskAt(t - vec3(d.x, 0, 0)),
                maskAt(t + vec3(0, d.y, 0)) - maskAt(t - vec3(0, d.y, 0)),
                maskAt(t + vec3(0, 0, d.z)) - maskAt(t - vec3(0, 0, d.z)));
  // Texture-space gradient to the patient frame: the transpose of the linear part of
  // patient-to-texture maps covectors.
  g = transpose(mat3(uPatientToTex)) * g;
  float len = length(g);
  return len > 1e-8 ? -g / len : vec3(0.0);  // outward: the mask falls outside
}

// Headlight-style key light, two-sided: CT surfaces have no inside or outside.
vec3 shade(vec3 rgb, vec3 nrm, vec3 viewDir) {
  if (dot(nrm, nrm) < 1e-6) return rgb * 0.75;
  float ndl = abs(dot(nrm, uLightDir));
  vec3 h = normalize(uLightDir - viewDir);
  float ndh = abs(dot(nrm, h));
  float n2 = ndh * ndh, n4 = n2 * n2, n8 = n4 * n4;
  float spec = n8 * n8 * n4;  // ndh^20 without pow's log/exp
  return rgb * (0.18 + 0.82 * ndl) + vec3(0.25 * spec);
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
    float block = float(uBlock);
    bvec3 moving = notEqual(dT, vec3(0.0));
    int i = 0;
    ivec3 lastCell = ivec3(-1);
    uint occ = 3u;
    float tBlockEnd = -1e30;
    float prevMask = 0.0;
    // Where the ray first enters the structure: context in front of it is drawn at uFrontFactor of
    // its opacity, so the structure stays the brightest thing where the user looks. Found by a
    // march of the structure's box at a voxel and a half (a thinner part it misses leaves the
    // context as it is there).
    float frontT = -1e30;
    if (RAY_STRUCTURE != 0 && uFrontFactor < 1.0) {
      vec3 ba = (uMaskBoxLo - oT) * inv, bb = (uMaskBoxHi - oT) * inv;
      vec3 bmin = min(ba, bb), bmax = max(ba, bb);
      float b0 = max(max(bmin.x, bmin.y), max(bmin.z, t0)), b1 = min(min(bmax.x, bmax.y), min(bmax.z, t1));
      for (float tb = b0; tb < b1; tb += 2.0 * uStepMm) {
        vec3 pb = origin + tb * dir;
        if (RAY_CLIP != 0 && dot(uClip.xyz, pb) > uClip.w) continue;
        if (maskAt(oT + tb * dT) >= 0.5) {
          frontT = tb;
          break;
        }
      }
    }
    while (i < count) {
      float tm = start + float(i) * uStepMm;
      vec3 pt = oT + tm * dT;
      if (uSkip != 0 && tm >= tBlockEnd) {
        ivec3 cell = clamp(ivec3(floor((pt * uDims - 0.5) / block)), ivec3(0), uBlocks - 1);
        if (cell != lastCell) {
          lastCell = cell;
          occ = texelFetch(uOccupancy, cell, 0).r;
        }
        // An empty block leaps over the cube of empty blocks around it (radius k - 1 blocks); the
        // outermost blocks reach beyond the box, so a ray leaving through them ends.
        int reach = (occ & 3u) == 0u ? int(occ >> 2) - 1 : 0;
        ivec3 c0 = cell - reach, c1 = cell + reach + 1;
        vec3 lo = mix(vec3(c0 * uBlock), vec3(-2.0), lessThanEqual(c0, ivec3(0)));
        vec3 hi = mix(vec3(c1 * uBlock), uDims + 2.0, greaterThanEqual(c1, uBlocks));
        vec3 bound = mix(lo, hi, greaterThan(dT, vec3(0.0)));
        vec3 te = mix(vec3(1e30), ((bound + 0.5) / uDims - oT) * inv, moving);
        float tExit = min(te.x, min(te.y, te.z));
        if ((occ & 3u) == 0u) {
          i = max(i + 1, int(ceil((tExit - start) / uStepMm - 1e-3)));
          prevMask = 0.0;
          continue;
        }
        tBlockEnd = tExit;
      }
      ++i;
      vec3 p = origin + tm * dir;
      if (RAY_CLIP != 0 && dot(uClip.xyz, p) > uClip.w) { prevMask = 0.0; continue; }
      float m = 0.0;
      if (RAY_STRUCTURE != 0 && (occ & 2u) != 0u) {
        m = maskAt(pt);
        if (m >= 0.5) {
          if (prevMask < 0.5) {
            // Entering the structure: one surface sample where the mask crosses 0.5, found by
            // two bisections of the step and a linear interpolation within the last half.
            vec3 a0 = pt - uStepMm * dT, a1 = pt;
            float m0 = prevMask, m1 = m;
            for (int b = 0; b < 2; ++b) {
              vec3 mid = 0.5 * (a0 + a1);
              float mm = maskAt(mid);
              if (mm >= 0.5) { a1 = mid; m1 = mm; } else { a0 = mid; m0 = mm; }
            }
            vec3 hit = mix(a0, a1, clamp((0.5 - m0) / max(m1 - m0, 1e-4), 0.0, 1.0));
            vec3 rgb = uHighlight;
            if (RAY_SHADING != 0) rgb = shade(rgb, maskNormal(hit), dir);
            acc.rgb += (1.0 - acc.a) * uStructureAlpha * clamp(rgb, 0.0, 1.0);
            acc.a += (1.0 - acc.a) * uStructureAlpha;
            if (acc.a > 0.98) break;
          }
          prevMask = m;
          continue;
        }
      }
      prevMask = m;
      if (RAY_MODE == 1 || (occ & 1u) == 0u || m > uMaskHalo) continue;
      vec4 v = texture(uVolume, pt);
      float hu = v.r * 32767.0;
      if (hu < uVisibleHu.x || hu > uVisibleHu.y) continue;
      vec3 g = v.gba;
      float strength = length(g) * uMaxStrength;
      float ramp = uSurface.y > uSurface.x ? smoothstep(uSurface.x, uSurface.y, strength) : step(uSurface.x, strength);
      float surface = mix(uSurface.z, 1.0, ramp);
      if (surface <= 0.0) continue;
      float d = 1e30;
      float n = 0.0;
      if (uHasField != 0) {
        d = texture(uField, oF + tm * dF).r;
        n = normalisedDistance(d);
        if (RAY_MODE == 3 && uBandN >= 0.0) {
          // Outline: the n over this sample's step nearest the band, so a band thinner than a step
          // is drawn wherever the step crosses it rather than where a sample happens to land in it.
          float na = normalisedDistance(texture(uField, oF + (tm - 0.5 * uStepMm) * dF).r);
          float nb = normalisedDistance(texture(uField, oF + (tm + 0.5 * uStepMm) * dF).r);
          n = clamp(uBandN, min(na, nb), max(na, nb));
        }
      }
      vec4 c = tableAt(hu, n);
      float alpha = c.a * surface * (tm < frontT ? uFrontFactor : 1.0);
      if (alpha <= 0.0) continue;
      vec3 rgb = c.rgb;
      if (RAY_SHADING != 0) {
        vec3 nrm = strength > 1e-3 ? g * (uMaxStrength / strength) : vec3(0.0);
        if (RAY_MODE == 2) {
          float ka = uLighting.y / pow(uLighting.x * min(max(d - uDistanceOffset, 0.0), 1e6) + 1.0, 2.0);
          rgb = rgb * (ka * uHighlight) + 0.2 * shade(rgb, nrm, dir);
          // Near the light k_a exceeds 1: scale the colour down as a whole rather than clipping
          // each channel, which would turn the orange rim yellow (red clips first, green catches up).
          rgb /= max(1.0, max(rgb.r, max(rgb.g, rgb.b)));
        } else {
          rgb = shade(rgb, nrm, dir);
        }
      } else if (RAY_MODE == 2) {
        float ka = uLighting.y / pow(uLighting.x * min(max(d - uDistanceOffset, 0.0), 1e6) + 1.0, 2.0);
        rgb = rgb * (ka * uHighlight + 0.25);
        rgb /= max(1.0, max(rgb.r, max(rgb.g, rgb.b)));
      }
      acc.rgb += (1.0 - acc.a) * alpha * clamp(rgb, 0.0, 1.0);
      acc.a += (1.0 - acc.a) * alpha;
      if (acc.a > 0.98) break;
    }
  }
  float bgA = uBackground.a * (1.0 - acc.a);
  float outA = acc.a + bgA;
  vec3 premul = acc.rgb + bgA * uBackground.rgb;
  return vec4(outA > 0.0 ? premul / outA : vec3(0.0), outA);
}
)";

const char* const kFragmentMain = R"(#version 430 core
out vec4 fragColor;
vec4 castRay(vec2 pixel);
void main() { fragColor = castRay(gl_FragCoord.xy); }
)";

// One work group per tile of 8 × 8 points of a sub-lattice (progressive.cpp): the points a level
// adds are q = uSubStep · (a, b) + uSubOffset in its lattice (the coarsest level: all points, step
// (1, 1); a finer level, the points no coarser level holds: its odd rows, step (1, 2) offset
// (0, 1), then the odd points of its even rows, step (2, 2) offset (1, 0)), so that every
// invocation of a SIMD group casts a ray, and neighbouring invocations cast neighbouring rays
// (llvmpipe runs a SIMD group until its slowest ray ends: coherent rays matter). Work group g casts
// the tile of rank uRankStart + g; ranks map to tiles by rank · uScramble mod tiles (1: in order). The pixel is q · 2^uLevel; its colour goes into the
// image of its level and of every finer one (where it is a lattice point too), so each level's
// image is complete when its level is. A whole image at once: level 0, step 1, tiles in order.
const char* const kComputeMain = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(rgba8, binding = 0) writeonly uniform image2D uLevelImage0;
layout(rgba8, binding = 1) writeonly uniform image2D uLevelImage1;
layout(rgba8, binding = 2) writeonly uniform image2D uLevelImage2;
layout(rgba8, binding = 3) writeonly uniform image2D uLevelImage3;
uniform vec2 uViewport;
uniform int uLevel;
uniform ivec2 uSubStep;
uniform ivec2 uSubOffset;
uniform int uRankStart;
uniform int uTilesWide;
uniform int uTiles;
uniform int uScramble;
vec4 castRay(vec2 pixel);

void main() {
  int rank = uRankStart + int(gl_WorkGroupID.x);
  if (rank >= uTiles) return;
  int tile = int((uint(rank) * uint(uScramble)) % uint(uTiles));
  ivec2 ab = ivec2(tile % uTilesWide, tile / uTilesWide) * 8 + ivec2(gl_LocalInvocationID.xy);
  ivec2 q = ab * uSubStep + uSubOffset;
  ivec2 p = q << uLevel;
  if (any(greaterThanEqual(p, ivec2(uViewport)))) return;
  vec4 c = castRay(vec2(p) + 0.5);
  if (uLevel == 3) imageStore(uLevelImage3, q, c);
  if (uLevel >= 2) imageStore(uLevelImage2, q << (uLevel - 2), c);
  if (uLevel >= 1) imageStore(uLevelImage1, q << (uLevel - 1), c);
  imageStore(uLevelImage0, p, c);
}
)";

// The selected structure's mask, smoothed by a [1 2 1]³/64 binomial so that its 0.5 level set is a
// smooth surface rather than voxel steps (see below for parts one voxel thin): written inside the box [uBoxMin, uBoxMax) of voxels, or
// cleared there (uClear) when the selection moves elsewhere.
const char* const kMaskShader = R"(#version 430 core
layout(local_size_x = 8, local_size_y = 8, local_size_z = 4) in;
layout(binding = 0) uniform usampler3D uLabels;
layout(r8, binding = 1) writeonly uniform image3D uMaskOut;
uniform uint uSelected;
uniform ivec3 uDims;
uniform ivec3 uBoxMin;
uniform ivec3 uBoxMax;
uniform int uClear;
void main() {
  ivec3 p = uBoxMin + ivec3(gl_GlobalInvocationID);
  if (any(greaterThanEqual(p, uBoxMax))) return;
  float m = 0.0;
  if (uClear == 0 && uSelected != 0u) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          ivec3 q = clamp(p + ivec3(dx, dy, dz), ivec3(0), uDims - 1);
          float w = float((2 - abs(dx)) * (2 - abs(dy)) * (2 - abs(dz)));
          if (texelFetch(uLabels, q, 0).r == uSelected) m += w;
        }
    m /= 64.0;
    // A labelled voxel the smoothing would drop below 0.5 (a part one voxel thin: a nerve, a canal
    // on a coarse grid, a sharp corner) is raised to 0.75, so it keeps a surface.
    if (m < 0.5 && texelFetch(uLabels, p, 0).r == uSelected) m = 0.75;
  }
  imageStore(uMaskOut, p, vec4(m));
}
)";

}  // namespace at::render::gl::shaders
