// Undo and redo of label edits, stored as compressed changes, never as copies of the label map.
//
// A LabelDelta holds the voxels one edit changed as runs of consecutive voxel indices sharing one
// (old, new) pair, varint-coded and deflated (zlib): a brush stroke or a threshold island costs
// bytes to kilobytes where a copy of a 256³ map costs 32 MB; a grow-from-seeds that relabels a
// whole volume costs what its label boundaries cost.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"
#include "volume/structure.h"

namespace at::segment {

struct LabelChange {
  std::size_t index = 0;  // voxel index on the label map's grid
  std::uint16_t before = 0, after = 0;
};

class LabelDelta {
 public:
  LabelDelta() = default;
  // The change from `before` to `after` (same grid: an assertion).
  static LabelDelta between(const LabelMap& before, const LabelMap& after);
  // From changes sorted by voxel index, one per voxel (changes with before == after are dropped).
  static LabelDelta fromSortedChanges(const std::vector<LabelChange>& changes);

  // Writes every changed voxel's old (undo) or new (redo) label.
  void undo(LabelMap& labels) const { apply(labels, false); }
  void redo(LabelMap& labels) const { apply(labels, true); }
  std::size_t voxels() const { return voxels_; }
  std::size_t bytes() const { return packed_.size(); }
  bool empty() const { return voxels_ == 0; }

 private:
  void apply(LabelMap& labels, bool forward) const;
  std::string packed_;  // deflated runs
  std::size_t voxels_ = 0;
};

// The edits of one label map, newest last. An edit may also change the structure list (adding,
// renaming, deleting a structure); both are undone and redone together.
class LabelHistory {
 public:
  struct Entry {
    std::string description;
    LabelDelta delta;
    std::optional<std::vector<Structure>> structuresBefore, structuresAfter;
  };

  // Records an edit already applied; drops what could be redone. Oldest edits are forgotten when
  // the history holds more than maxBytes() of deltas.
  void record(Entry entry);
  bool canUndo() const { return done_ > 0; }
  bool canRedo() const { return done_ < entries_.size(); }
  // Reverts the newest edit (labels and, if it changed them, structures); returns its description,
  // or an error when there is nothing to undo.
  Result<std::string> undo(LabelMap& labels, std::vector<Structure>& structures);
  Result<std::string> redo(LabelMap& labels, std::vector<Structure>& structures);
  std::size_t bytes() const;
  std::size_t size() const { return entries_.size(); }
  std::size_t maxBytes() const { return maxBytes_; }
  void setMaxBytes(std::size_t bytes) { maxBytes_ = bytes; }

 private:
  std::vector<Entry> entries_;
  std::size_t done_ = 0;  // entries_[0 … done_) are applied
  std::size_t maxBytes_ = std::size_t(256) << 20;
};

}  // namespace at::segment
