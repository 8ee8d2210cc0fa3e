// Review scheduling with Leitner boxes: a right answer moves the structure to the next box and a
// longer interval; a wrong one sends it back to box 1, due again soon (same session).
#pragma once

#include <array>
#include <vector>

#include "lessons/repositories.h"

namespace at::lessons {

inline constexpr int kLeitnerBoxes = 5;

struct LeitnerSchedule {
  // Interval after a right answer that lands in box b (index b − 1): 1, 2, 4, 8, 16 days.
  std::array<UnixSeconds, kLeitnerBoxes> intervals{86400, 2 * 86400, 4 * 86400, 8 * 86400, 16 * 86400};
  UnixSeconds relearnDelay = 600;  // after a wrong answer: due again in 10 minutes, box 1
};

// The progress after answering. Right: box = min(box + 1, kLeitnerBoxes) (a first right answer
// lands in box 2: it was known without practice), due = now + intervals[box − 1]. Wrong: box 1,
// due = now + relearnDelay. Counters and lastAnsweredAt updated.
StructureProgress scheduleAnswer(StructureProgress before, bool correct, UnixSeconds now,
                                 const LeitnerSchedule& schedule = {});

// Structures due at `now` (dueAt <= now, answered at least once), earliest due first, ties by id.
std::vector<StructureProgress> dueForReview(std::vector<StructureProgress> all, UnixSeconds now);

}  // namespace at::lessons
