#include "lessons/scheduling.h"

#include <algorithm>
#include <string>

namespace at::lessons {

std::int64_t fastAnswerMs(quiz::QuestionKind kind) {
  switch (kind) {
    case quiz::QuestionKind::Locate:
    case quiz::QuestionKind::Identify:
      return 4000;
    case quiz::QuestionKind::Name:
    case quiz::QuestionKind::Relation:
      return 8000;
    case quiz::QuestionKind::Order:
      return 15000;
  }
  return 0;
}

Rating ratingFor(bool correct, double score, quiz::QuestionKind kind, std::int64_t latencyMs) {
  if (!correct) return score >= 0.5 ? Rating::Hard : Rating::Again;
  if (latencyMs > 0 && latencyMs <= fastAnswerMs(kind)) return Rating::Easy;
  return Rating::Good;
}

StructureProgress scheduleAnswer(StructureProgress before, Rating rating, bool correct, UnixSeconds now,
                                 const Fsrs& fsrs) {
  StructureProgress after = before;
  // A fuzz value in [0, 1) fixed by who, what and which review: replays give the same schedule.
  // (FNV-1a, the same on every platform.)
  std::uint64_t h = 14695981039346656037ull;
  for (char c : std::to_string(before.userId) + "/" + before.structureId + "/" + std::to_string(before.memory.reviews))
    h = (h ^ std::uint8_t(c)) * 1099511628211ull;
  const double fuzz = double(h >> 11) / double(1ull << 53);
  after.memory = fsrs.review(before.memory, rating, std::max(now, before.memory.lastReview), fuzz);
  after.answered += 1;
  if (correct) after.correct += 1;
  return after;
}

std::vector<StructureProgress> dueForReview(std::vector<StructureProgress> all, UnixSeconds now) {
  std::erase_if(all, [&](const StructureProgress& p) {
    return p.answered == 0 || p.memory.phase == MemoryPhase::New || p.memory.due > now;
  });
  std::sort(all.begin(), all.end(), [](const StructureProgress& a, const StructureProgress& b) {
    return a.memory.due != b.memory.due ? a.memory.due < b.memory.due : a.structureId < b.structureId;
  });
  return all;
}

}  // namespace at::lessons
