#include "volume/body_mask.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace at {

namespace {

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

// Keeps the largest 6-connected component of the non-zero voxels.
void keepLargestComponent(std::vector<std::uint8_t>& m, const Dims& d) {
  std::vector<int> comp(m.size(), 0);
  std::vector<std::size_t> stack;
  int next = 0, best = 0;
  std::size_t bestSize = 0;
  const long sx = 1, sy = d.x, sz = long(d.x) * d.y;
  for (std::size_t seed = 0; seed < m.size(); ++seed) {
    if (!m[seed] || comp[seed]) continue;
    ++next;
    std::size_t size = 0;
    stack.push_back(seed);
    comp[seed] = next;
    while (!stack.empty()) {
      const std::size_t p = stack.back();
      stack.pop_back();
      ++size;
      const int i = int(p % std::size_t(d.x)), j = int((p / std::size_t(d.x)) % std::size_t(d.y)),
                k = int(p / std::size_t(sz));
      const long nb[6] = {i > 0 ? -sx : 0, i + 1 < d.x ? sx : 0, j > 0 ? -sy : 0, j + 1 < d.y ? sy : 0,
                          k > 0 ? -sz : 0, k + 1 < d.z ? sz : 0};
      for (long o : nb) {
        if (o == 0) continue;
        const std::size_t q = std::size_t(long(p) + o);
        if (m[q] && !comp[q]) {
          comp[q] = next;
          stack.push_back(q);
        }
      }
    }
    if (size > bestSize) {
      bestSize = size;
      best = next;
    }
  }
  for (std::size_t p = 0; p < m.size(); ++p) m[p] = std::uint8_t(comp[p] == best && best != 0);
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
  keepLargestComponent(m, g.dims);
  bool any = std::any_of(m.begin(), m.end(), [](std::uint8_t v) { return v != 0; });
  if (!any) {  // everything thinner than the opening: the unopened largest component
    m = thresholded;
    keepLargestComponent(m, g.dims);
  } else {
    boxFilter(m, g.dims, r, false);
    for (std::size_t p = 0; p < m.size(); ++p) m[p] = std::uint8_t(m[p] && thresholded[p]);
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
