// LabelEditor::splitIslands (label_editor.h): a structure's disconnected pieces as structures.
#include <algorithm>
#include <cstdio>
#include <deque>

#include "core/strings.h"
#include "segment/distance_map.h"
#include "segment/label_editor.h"
#include "volume/mask.h"

namespace at::segment {

namespace {

// The 6-connected components of `mask`: a component number per voxel (0: not in the mask, 1 … n)
// and each component's voxel count (index 0 unused).
struct Components {
  std::vector<std::uint32_t> id;
  std::vector<std::size_t> size;
};

Components components(const Mask& mask) {
  const Dims d = mask.dims();
  Components c;
  c.id.assign(mask.voxels.size(), 0);
  c.size.push_back(0);
  const std::size_t nx = std::size_t(d.x), nxy = nx * std::size_t(d.y);
  std::deque<std::size_t> queue;
  for (std::size_t start = 0; start < mask.voxels.size(); ++start) {
    if (!mask.voxels[start] || c.id[start]) continue;
    const std::uint32_t number = std::uint32_t(c.size.size());
    c.size.push_back(0);
    c.id[start] = number;
    queue.push_back(start);
    while (!queue.empty()) {
      const std::size_t v = queue.front();
      queue.pop_front();
      ++c.size[number];
      const int x = int(v % nx), y = int(v / nx % std::size_t(d.y)), z = int(v / nxy);
      const int next[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z}, {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
      for (const auto& n : next) {
        if (!d.contains(n[0], n[1], n[2])) continue;
        const std::size_t w = d.index(n[0], n[1], n[2]);
        if (mask.voxels[w] && !c.id[w]) c.id[w] = number, queue.push_back(w);
      }
    }
  }
  return c;
}

}  // namespace

Result<IslandSplit> LabelEditor::splitIslands(std::uint16_t label, double minDiameterMm, std::size_t minVoxels) {
  if (auto ok = requireStructure(label); !ok) return tl::unexpected(ok.error());
  if (!(minDiameterMm >= 0)) return fail("split islands: the minimum diameter must be >= 0 mm");
  const Structure original = *find(label);
  Mask mask(labels_.geometry, 0);
  for (std::size_t i = 0; i < mask.voxels.size(); ++i) mask.voxels[i] = labels_.voxels[i] == label;
  const double r = 0.5 * minDiameterMm;
  const Components parts = components(minDiameterMm > 0 ? erode(mask, r) : mask);
  // The pieces by size, largest first; each piece's voxels are its component (grown back by r and
  // kept inside the structure when bridges were cut).
  std::vector<std::uint32_t> order;
  for (std::uint32_t n = 1; n < parts.size.size(); ++n) order.push_back(n);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return parts.size[a] > parts.size[b]; });
  std::vector<std::uint32_t> pieceOf(mask.voxels.size(), 0);  // 0: no piece (bridge) or the kept one
  std::vector<std::uint32_t> pieces;                          // component numbers of new structures
  std::vector<std::size_t> pieceVoxels;
  std::vector<std::uint8_t> taken(mask.voxels.size(), 0);
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    const std::uint32_t n = order[rank];
    Mask piece(labels_.geometry, 0);
    for (std::size_t i = 0; i < piece.voxels.size(); ++i) piece.voxels[i] = parts.id[i] == n;
    if (minDiameterMm > 0) piece = dilate(piece, r);
    std::size_t voxels = 0;
    for (std::size_t i = 0; i < piece.voxels.size(); ++i)
      if (piece.voxels[i] && mask.voxels[i] && !taken[i]) ++voxels;
    if (rank > 0 && voxels < std::max<std::size_t>(minVoxels, 1)) continue;
    for (std::size_t i = 0; i < piece.voxels.size(); ++i)
      if (piece.voxels[i] && mask.voxels[i] && !taken[i]) taken[i] = 1, pieceOf[i] = rank == 0 ? 0 : n;
    if (rank > 0) pieces.push_back(n), pieceVoxels.push_back(voxels);
  }
  if (pieces.empty()) {
    std::string sizes;
    for (std::size_t k = 0; k < std::min<std::size_t>(order.size(), 3); ++k)
      sizes += (k ? ", " : "") + std::to_string(parts.size[order[k]]);
    return fail("split islands: '" + original.displayName + "' has " + std::to_string(order.size()) +
                " piece(s)" + (sizes.empty() ? "" : " (" + sizes + " voxels)") +
                (minDiameterMm > 0 ? " after cutting bridges thinner than " + std::to_string(minDiameterMm) + " mm" : "") +
                ", no second one of at least " + std::to_string(std::max<std::size_t>(minVoxels, 1)) + " voxels");
  }
  // New structures, named after the original with the piece's rank.
  const std::vector<Structure> before = structures_;
  std::uint16_t next = 1;
  for (const Structure& s : structures_) next = std::max<std::uint16_t>(next, std::uint16_t(s.label + 1));
  for (std::uint16_t v : labels_.voxels) next = std::max<std::uint16_t>(next, std::uint16_t(v + 1));
  if (std::size_t(next) + pieces.size() >= 0xFFFF) return fail("split islands: no label values left for the pieces");
  IslandSplit out;
  std::vector<std::uint16_t> labelOfComponent(parts.size.size(), 0);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    std::string name;
    for (int suffix = int(k) + 2;; ++suffix) {
      name = original.displayName + " (" + std::to_string(suffix) + ")";
      const std::string id = str::identifier(name);
      if (std::none_of(structures_.begin(), structures_.end(),
                       [&](const Structure& s) { return s.displayName == name || s.id == id; }))
        break;
    }
    Structure s;
    s.label = std::uint16_t(next + k);
    s.displayName = name;
    s.id = str::identifier(name);
    s.colour = paletteColour(s.label);
    s.system = original.system;
    structures_.push_back(s);
    labelOfComponent[pieces[k]] = s.label;
    out.newLabels.push_back(s.label);
  }
  std::vector<std::pair<std::size_t, std::uint16_t>> changes;
  for (std::size_t i = 0; i < pieceOf.size(); ++i)
    if (pieceOf[i]) changes.push_back({i, labelOfComponent[pieceOf[i]]});
  char what[160];
  std::snprintf(what, sizeof what, "split islands of '%s' into %zu structures", original.displayName.c_str(), pieces.size() + 1);
  out.summary = commit(what, changes, before);
  return out;
}

}  // namespace at::segment
