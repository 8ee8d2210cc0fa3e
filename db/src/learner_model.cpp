#include "learner_model.h"

namespace at::db {

using namespace at::lessons;

// The learner-model half of recording an answer, inside the caller's transaction: the structure's
// memory state, its review-log entry, the user's ability and the question's difficulty.
Status writeLearnerModel(Database& d, const LearnerUpdate& u, const GradedAnswer& answer, AnswerSource source,
                         std::int64_t sourceId) {
  const StructureProgress& p = u.progress;
  if (p.memory.phase == MemoryPhase::New) return fail("a memory state after an answer cannot be new");
  auto progress = d.prepare(
      "INSERT INTO memory_states (user_id, structure, phase, step, stability, difficulty, due_at, last_review_at,"
      " reviews, lapses, answered, correct) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12)"
      " ON CONFLICT (user_id, structure) DO UPDATE SET phase = excluded.phase, step = excluded.step,"
      " stability = excluded.stability, difficulty = excluded.difficulty, due_at = excluded.due_at,"
      " last_review_at = excluded.last_review_at, reviews = excluded.reviews, lapses = excluded.lapses,"
      " answered = excluded.answered, correct = excluded.correct");
  if (!progress) return tl::unexpected(progress.error());
  progress->bind(1, p.userId)
      .bind(2, p.structureId)
      .bind(3, toString(p.memory.phase))
      .bind(4, p.memory.step)
      .bind(5, p.memory.stability)
      .bind(6, p.memory.difficulty)
      .bind(7, p.memory.due)
      .bind(8, p.memory.lastReview)
      .bind(9, p.memory.reviews)
      .bind(10, p.memory.lapses)
      .bind(11, p.answered)
      .bind(12, p.correct);
  if (auto s = progress->run(); !s) return s;

  auto log = d.prepare(
      "INSERT INTO review_log (user_id, structure, question_id, source, source_id, reviewed_at, rating, correct,"
      " score, latency_ms, phase_before, elapsed_days, phase_after, stability, difficulty, due_at)"
      " VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)");
  if (!log) return tl::unexpected(log.error());
  const bool first = u.memoryBefore.phase == MemoryPhase::New;
  log->bind(1, p.userId)
      .bind(2, p.structureId)
      .bind(3, answer.questionId)
      .bind(4, toString(source))
      .bind(5, sourceId)
      .bind(6, answer.answeredAt)
      .bind(7, int(u.rating))
      .bind(8, answer.correct ? 1 : 0)
      .bind(9, answer.score)
      .bind(10, answer.latencyMs)
      .bind(11, toString(u.memoryBefore.phase))
      .bind(12, first ? std::optional<std::int64_t>() : std::optional<std::int64_t>(
                                                              Fsrs::elapsedDays(u.memoryBefore.lastReview, answer.answeredAt)))
      .bind(13, toString(p.memory.phase))
      .bind(14, p.memory.stability)
      .bind(15, p.memory.difficulty)
      .bind(16, p.memory.due);
  if (auto s = log->run(); !s) return s;

  auto ability = d.prepare(
      "INSERT INTO user_ability (user_id, rating, answered) VALUES (?1, ?2, 1)"
      " ON CONFLICT (user_id) DO UPDATE SET rating = excluded.rating, answered = user_ability.answered + 1");
  if (!ability) return tl::unexpected(ability.error());
  ability->bind(1, p.userId).bind(2, u.abilityAfter);
  if (auto s = ability->run(); !s) return s;

  auto difficulty = d.prepare(
      "INSERT INTO question_stats (question_id, difficulty, answered) VALUES (?1, ?2, 1)"
      " ON CONFLICT (question_id) DO UPDATE SET difficulty = excluded.difficulty, answered = question_stats.answered + 1");
  if (!difficulty) return tl::unexpected(difficulty.error());
  difficulty->bind(1, answer.questionId).bind(2, u.difficultyAfter);
  return difficulty->run();
}

}  // namespace at::db
