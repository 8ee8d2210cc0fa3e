// Compressed label deltas and the undo/redo history.
//
// Run coding, before deflate: per run, varint(gap from the end of the previous run),
// varint(length − 1), then the old and the new label as two bytes each (little endian).
#include "segment/label_history.h"

#include <zlib.h>

#include <cassert>
#include <stdexcept>

namespace at::segment {

namespace {

void putVarint(std::string& out, std::uint64_t v) {
  while (v >= 0x80) {
    out.push_back(char(std::uint8_t(v) | 0x80));
    v >>= 7;
  }
  out.push_back(char(std::uint8_t(v)));
}

std::uint64_t getVarint(const std::string& in, std::size_t& at) {
  std::uint64_t v = 0;
  for (int shift = 0;; shift += 7) {
    const std::uint8_t b = std::uint8_t(in.at(at++));
    v |= std::uint64_t(b & 0x7F) << shift;
    if (!(b & 0x80)) return v;
  }
}

void putLabel(std::string& out, std::uint16_t v) {
  out.push_back(char(v & 0xFF));
  out.push_back(char(v >> 8));
}

std::uint16_t getLabel(const std::string& in, std::size_t& at) {
  const std::uint16_t v = std::uint16_t(std::uint8_t(in.at(at)) | (std::uint8_t(in.at(at + 1)) << 8));
  at += 2;
  return v;
}

// Deflated runs, prefixed by the plain size (varint). Compression failing is a programmer error
// (zlib fails only on bad parameters or out of memory, which throws bad_alloc here first).
std::string deflateRuns(const std::string& plain) {
  std::string out;
  putVarint(out, plain.size());
  uLongf size = compressBound(uLong(plain.size()));
  const std::size_t head = out.size();
  out.resize(head + size);
  const int z = compress2(reinterpret_cast<Bytef*>(out.data() + head), &size,
                          reinterpret_cast<const Bytef*>(plain.data()), uLong(plain.size()), Z_BEST_SPEED);
  if (z != Z_OK) throw std::runtime_error("label history: zlib could not compress a delta");
  out.resize(head + size);
  return out;
}

std::string inflateRuns(const std::string& packed) {
  std::size_t at = 0;
  const std::size_t plainSize = std::size_t(getVarint(packed, at));
  std::string plain(plainSize, '\0');
  uLongf size = uLongf(plainSize);
  const int z = uncompress(reinterpret_cast<Bytef*>(plain.data()), &size,
                           reinterpret_cast<const Bytef*>(packed.data() + at), uLong(packed.size() - at));
  if (z != Z_OK || size != plainSize) throw std::runtime_error("label history: a stored delta is corrupt");
  return plain;
}

// Builds the runs as changes arrive in increasing index order.
class RunWriter {
 public:
  void add(std::size_t index, std::uint16_t before, std::uint16_t after) {
    if (before == after) return;
    ++voxels_;
    if (open_ && index == start_ + length_ && before == before_ && after == after_) {
      ++length_;
      return;
    }
    flush();
    open_ = true;
    start_ = index;
    length_ = 1;
    before_ = before;
    after_ = after;
  }
  std::string finish(std::size_t& voxels) {
    flush();
    voxels = voxels_;
    return plain_;
  }

 private:
  void flush() {
    if (!open_) return;
    putVarint(plain_, start_ - end_);
    putVarint(plain_, length_ - 1);
    putLabel(plain_, before_);
    putLabel(plain_, after_);
    end_ = start_ + length_;
    open_ = false;
  }
  std::string plain_;
  bool open_ = false;
  std::size_t start_ = 0, length_ = 0, end_ = 0, voxels_ = 0;
  std::uint16_t before_ = 0, after_ = 0;
};

}  // namespace

LabelDelta LabelDelta::between(const LabelMap& before, const LabelMap& after) {
  assert(before.voxels.size() == after.voxels.size() && "LabelDelta::between: label maps on different grids");
  RunWriter runs;
  for (std::size_t i = 0; i < before.voxels.size(); ++i) runs.add(i, before.voxels[i], after.voxels[i]);
  LabelDelta d;
  const std::string plain = runs.finish(d.voxels_);
  if (d.voxels_) d.packed_ = deflateRuns(plain);
  return d;
}

LabelDelta LabelDelta::fromSortedChanges(const std::vector<LabelChange>& changes) {
  RunWriter runs;
  for (std::size_t i = 0; i < changes.size(); ++i) {
    assert((i == 0 || changes[i].index > changes[i - 1].index) && "LabelDelta: changes must be sorted, one per voxel");
    runs.add(changes[i].index, changes[i].before, changes[i].after);
  }
  LabelDelta d;
  const std::string plain = runs.finish(d.voxels_);
  if (d.voxels_) d.packed_ = deflateRuns(plain);
  return d;
}

void LabelDelta::apply(LabelMap& labels, bool forward) const {
  if (voxels_ == 0) return;
  const std::string plain = inflateRuns(packed_);
  std::size_t at = 0, end = 0;
  while (at < plain.size()) {
    const std::size_t start = end + std::size_t(getVarint(plain, at));
    const std::size_t length = std::size_t(getVarint(plain, at)) + 1;
    const std::uint16_t before = getLabel(plain, at), after = getLabel(plain, at);
    assert(start + length <= labels.voxels.size() && "LabelDelta: applied to a smaller label map");
    std::fill(labels.voxels.begin() + std::ptrdiff_t(start), labels.voxels.begin() + std::ptrdiff_t(start + length),
              forward ? after : before);
    end = start + length;
  }
}

void LabelHistory::record(Entry entry) {
  entries_.resize(done_);
  entries_.push_back(std::move(entry));
  done_ = entries_.size();
  while (entries_.size() > 1 && bytes() > maxBytes_) {
    entries_.erase(entries_.begin());
    --done_;
  }
}

Result<std::string> LabelHistory::undo(LabelMap& labels, std::vector<Structure>& structures) {
  if (!canUndo()) return fail(ErrorKind::NotFound, "nothing to undo");
  const Entry& e = entries_[--done_];
  e.delta.undo(labels);
  if (e.structuresBefore) structures = *e.structuresBefore;
  return e.description;
}

Result<std::string> LabelHistory::redo(LabelMap& labels, std::vector<Structure>& structures) {
  if (!canRedo()) return fail(ErrorKind::NotFound, "nothing to redo");
  const Entry& e = entries_[done_++];
  e.delta.redo(labels);
  if (e.structuresAfter) structures = *e.structuresAfter;
  return e.description;
}

std::size_t LabelHistory::bytes() const {
  std::size_t total = 0;
  for (const Entry& e : entries_) total += e.delta.bytes();
  return total;
}

}  // namespace at::segment
