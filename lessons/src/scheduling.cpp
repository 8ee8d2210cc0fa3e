#include "lessons/scheduling.h"

#include <algorithm>

namespace at::lessons {

StructureProgress scheduleAnswer(StructureProgress before, bool correct, UnixSeconds now,
                                 const LeitnerSchedule& schedule) {
  StructureProgress after = before;
  after.answered += 1;
  after.lastAnsweredAt = now;
  if (correct) {
    after.correct += 1;
    after.box = std::clamp(std::max(before.box, 1) + 1, 1, kLeitnerBoxes);
    after.dueAt = now + schedule.intervals[after.box - 1];
  } else {
    after.box = 1;
    after.dueAt = now + schedule.relearnDelay;
  }
  return after;
}

std::vector<StructureProgress> dueForReview(std::vector<StructureProgress> all, UnixSeconds now) {
  std::erase_if(all, [&](const StructureProgress& p) { return p.answered == 0 || p.dueAt > now; });
  std::sort(all.begin(), all.end(), [](const StructureProgress& a, const StructureProgress& b) {
    return a.dueAt != b.dueAt ? a.dueAt < b.dueAt : a.structureId < b.structureId;
  });
  return all;
}

}  // namespace at::lessons
