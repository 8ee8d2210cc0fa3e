#include "volume/body_mask.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace at {

namespace {

// An eroded piece apart from the body's of at least this volume is another object (a headrest, a
// table) that keeps the thresholded voxels nearer to it; smaller ones (a nose tip whose core
// survived the erosion) are reached from whichever core is nearer, like any thresholded voxel.
constexpr double kMinObjectCoreMm3 = 1000.0;

// Min (erode) or max (dilate) of a 0/1 mask over a box of half-width r[a] along each axis:
// separable, one pass per axis with a running count.
void boxFilter(std::vector<std::uint8_t>& m, const Dims& d, const int r[3], bool erode) {
  const int n[3] = {d.x, d.y, d.z};
  const std::size_t strideOf[3] = {1, std::size_t(d.x), std::size_t(d.x) * std::size_t(d.y)};
  std::vector<std::uint8_t> line, out;
  for (int a = 0; a < 3; ++a) {
    if (r[a] <= 0) continue;
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    line.resize(std::size_t(n[a]));
    out.resize(std::size_t(n[a]));
    for (int v = 0; v < n[c]; ++v)
      for (int u = 0; u < n[b]; ++u) {
        const std::size_t base = std::size_t(u) * strideOf[b] + std::size_t(v) * strideOf[c];
        for (int i = 0; i < n[a]; ++i) line[std::size_t(i)] = m[base + std::size_t(i) * strideOf[a]];
        // ones in the window [i − r, i + r] (outside the grid counts as 0 for dilation, 1 for erosion)
        int ones = 0;
        const auto valueAt = [&](int i) { return (i < 0 || i >= n[a]) ? (erode ? 1 : 0) : int(line[std::size_t(i)]); };
        for (int i = -r[a]; i <= r[a]; ++i) ones += valueAt(i);
        for (int i = 0; i < n[a]; ++i) {
          out[std::size_t(i)] = erode ? std::uint8_t(ones == 2 * r[a] + 1) : std::uint8_t(ones > 0);
          ones += valueAt(i + r[a] + 1) - valueAt(i - r[a]);
        }
        for (int i = 0; i < n[a]; ++i) m[base + std::size_t(i) * strideOf[a]] = out[std::size_t(i)];
      }
  }
}

// The 6-connected components of the non-zero voxels: each voxel's component number (0 where the
// mask is 0, else 1 …) and each component's size (index 0 unused).
struct Components {
  std::vector<int> of;
  std::vector<std::size_t> sizes{0};
};

// Calls visit(q) for each 6-neighbour q of voxel p that lies on the grid (p's position worked out
// once).
template <class Visit>
void forEachNeighbour(std::size_t p, const Dims& d, Visit&& visit) {
  const std::size_t sy = std::size_t(d.x), sz = std::size_t(d.x) * std::size_t(d.y);
  const int i = int(p % sy), j = int((p / sy) % std::size_t(d.y)), k = int(p / sz);
  if (i > 0) visit(p - 1);
  if (i + 1 < d.x) visit(p + 1);
  if (j > 0) visit(p - sy);
  if (j + 1 < d.y) visit(p + sy);
  if (k > 0) visit(p - sz);
  if (k + 1 < d.z) visit(p + sz);
}

Components componentsOf(const std::vector<std::uint8_t>& m, const Dims& d) {
  Components c;
  c.of.assign(m.size(), 0);
  std::vector<std::size_t> stack;
  for (std::size_t seed = 0; seed < m.size(); ++seed) {
    if (!m[seed] || c.of[seed]) continue;
    const int id = int(c.sizes.size());
    std::size_t size = 0;
    c.of[seed] = id;
    stack.push_back(seed);
    while (!stack.empty()) {
      const std::size_t p = stack.back();
      stack.pop_back();
      ++size;
      forEachNeighbour(p, d, [&](std::size_t q) {
        if (m[q] && !c.of[q]) {
          c.of[q] = id;
          stack.push_back(q);
        }
      });
    }
    c.sizes.push_back(size);
  }
  return c;
}

// Keeps the largest 6-connected component of the non-zero voxels.
void keepLargestComponent(std::vector<std::uint8_t>& m, const Dims& d) {
  const Components c = componentsOf(m, d);
  const auto best = std::max_element(c.sizes.begin(), c.sizes.end()) - c.sizes.begin();
  for (std::size_t p = 0; p < m.size(); ++p) m[p] = std::uint8_t(best != 0 && c.of[p] == int(best));
}

// Shares the thresholded voxels between the body's core and the other objects' cores: a
// breadth-first growth inside `thresholded` (6-connected) from all cores at once, each voxel
// going to the core that reaches it in the fewest steps. Returns the body's voxels. A thin part
// reached only from the body (the nose, the ears) is body however far it reaches; a thin contact
// between the body and a headrest is split where the two growths meet.
std::vector<std::uint8_t> growBodyAgainstObjects(const std::vector<std::uint8_t>& thresholded, const Components& cores,
                                                 int bodyCore, std::size_t minObjectCore, const Dims& d) {
  enum : std::uint8_t { kUnreached = 0, kBody = 1, kObject = 2 };
  std::vector<std::uint8_t> owner(thresholded.size(), kUnreached);
  const auto competes = [&](int c) { return c == bodyCore || (c != 0 && cores.sizes[std::size_t(c)] >= minObjectCore); };
  for (std::size_t p = 0; p < thresholded.size(); ++p)
    if (competes(cores.of[p])) owner[p] = cores.of[p] == bodyCore ? kBody : kObject;
  // Step by step, keeping only the voxels reached at the last step (a surface, not a volume): the
  // growth starts from the cores' voxels next to a voxel no core owns.
  std::vector<std::size_t> front, next;
  for (std::size_t p = 0; p < thresholded.size(); ++p) {
    if (owner[p] == kUnreached) continue;
    bool edge = false;
    forEachNeighbour(p, d, [&](std::size_t q) { edge = edge || (owner[q] == kUnreached && thresholded[q]); });
    if (edge) front.push_back(p);
  }
  while (!front.empty()) {
    next.clear();
    for (const std::size_t p : front)
      forEachNeighbour(p, d, [&](std::size_t q) {
        if (!thresholded[q] || owner[q] != kUnreached) return;
        owner[q] = owner[p];
        next.push_back(q);
      });
    front.swap(next);
  }
  for (auto& v : owner) v = std::uint8_t(v == kBody);
  return owner;
}

// Fills holes slice by slice across axis `a`: background not 4-connected to the slice's border
// becomes body.
void fillSlices(std::vector<std::uint8_t>& m, const Dims& d, int a) {
  const int n[3] = {d.x, d.y, d.z};
  const std::size_t strideOf[3] = {1, std::size_t(d.x), std::size_t(d.x) * std::size_t(d.y)};
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  std::vector<std::uint8_t> outside;
  std::vector<int> stack;
  for (int s = 0; s < n[a]; ++s) {
    const std::size_t base = std::size_t(s) * strideOf[a];
    const auto at = [&](int u, int v) { return base + std::size_t(u) * strideOf[b] + std::size_t(v) * strideOf[c]; };
    outside.assign(std::size_t(n[b]) * std::size_t(n[c]), 0);
    const auto push = [&](int u, int v) {
      const std::size_t q = std::size_t(u) + std::size_t(v) * std::size_t(n[b]);
      if (outside[q] || m[at(u, v)]) return;
      outside[q] = 1;
      stack.push_back(int(q));
    };
    for (int u = 0; u < n[b]; ++u) {
      push(u, 0);
      push(u, n[c] - 1);
    }
    for (int v = 0; v < n[c]; ++v) {
      push(0, v);
      push(n[b] - 1, v);
    }
    while (!stack.empty()) {
      const int q = stack.back();
      stack.pop_back();
      const int u = q % n[b], v = q / n[b];
      if (u > 0) push(u - 1, v);
      if (u + 1 < n[b]) push(u + 1, v);
      if (v > 0) push(u, v - 1);
      if (v + 1 < n[c]) push(u, v + 1);
    }
    for (int v = 0; v < n[c]; ++v)
      for (int u = 0; u < n[b]; ++u)
        if (!outside[std::size_t(u) + std::size_t(v) * std::size_t(n[b])]) m[at(u, v)] = 1;
  }
}

}  // namespace

Mask bodyMask(const Volume& volume, double tissueLevel, double neckMm) {
  const Geometry& g = volume.geometry;
  Mask out(g, 0);
  std::vector<std::uint8_t>& m = out.voxels;
  for (std::size_t p = 0; p < m.size(); ++p) m[p] = std::uint8_t(double(volume.voxels[p]) >= tissueLevel);
  int r[3];
  for (int a = 0; a < 3; ++a) r[a] = std::max(0, int(std::lround(neckMm / std::max(1e-6, g.spacingMm[a]))));
  const std::vector<std::uint8_t> thresholded = m;
  boxFilter(m, g.dims, r, true);
  const Components cores = componentsOf(m, g.dims);
  const auto bodyCore = std::max_element(cores.sizes.begin(), cores.sizes.end()) - cores.sizes.begin();
  if (bodyCore == 0) {  // everything thinner than the erosion: the unopened largest component
    m = thresholded;
    keepLargestComponent(m, g.dims);
  } else {
    const double voxelMm3 = g.spacingMm[0] * g.spacingMm[1] * g.spacingMm[2];
    const auto minObjectCore = std::size_t(std::ceil(kMinObjectCoreMm3 / std::max(1e-9, voxelMm3)));
    m = growBodyAgainstObjects(thresholded, cores, int(bodyCore), std::max<std::size_t>(1, minObjectCore), g.dims);
  }
  for (int a = 0; a < 3; ++a) fillSlices(m, g.dims, a);
  return out;
}

std::size_t clearOutsideBody(Volume& volume, const Mask& body, std::int16_t background) {
  std::size_t changed = 0;
  if (body.voxels.size() != volume.voxels.size()) return 0;
  for (std::size_t p = 0; p < volume.voxels.size(); ++p)
    if (!body.voxels[p] && volume.voxels[p] != background) {
      volume.voxels[p] = background;
      ++changed;
    }
  return changed;
}

}  // namespace at
