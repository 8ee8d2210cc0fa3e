// Review scheduling: FSRS-6 (lessons/fsrs.h) per user × structure. Every graded answer — in a
// lesson, a review or an exam — becomes an FSRS rating and moves the structure's memory state.
//
// How a graded answer becomes a rating (ratingFor):
//   wrong, less than half credit            → Again   (forgotten: relearn in 10 minutes)
//   wrong with at least half credit         → Hard    (an order question partly right)
//   right                                   → Good
//   right and fast (a measured response time within fastAnswerMs of its kind) → Easy
// A response time of 0 means "not measured" (answers read from a file) and never counts as fast.
#pragma once

#include <cstdint>
#include <vector>

#include "lessons/fsrs.h"
#include "lessons/repositories.h"
#include "quiz/question.h"

namespace at::lessons {

// The response time under which a right answer counts as effortless recall (Easy): 4 s to click
// or choose, 8 s to type a name or pick a relation, 15 s to arrange an order.
std::int64_t fastAnswerMs(quiz::QuestionKind kind);
Rating ratingFor(bool correct, double score, quiz::QuestionKind kind, std::int64_t latencyMs);

// The progress after answering with `rating` at `now`: the FSRS review of its memory state (fuzz
// drawn deterministically from the user, structure and review count), counters updated.
StructureProgress scheduleAnswer(StructureProgress before, Rating rating, bool correct, UnixSeconds now,
                                 const Fsrs& fsrs);

// Structures due at `now` (answered at least once, memory.due <= now), earliest due first, ties by id.
std::vector<StructureProgress> dueForReview(std::vector<StructureProgress> all, UnixSeconds now);

}  // namespace at::lessons
