// FSRS-6, the Free Spaced Repetition Scheduler (the scheduler Anki uses), written from its published
// formulas: a memory state per student × structure — stability S (days until recall probability
// falls to 90 %), difficulty D (1..10) — moved by each graded answer, and the interval that keeps
// the predicted recall at the desired retention. Defaults are the reference implementation's
// (py-fsrs / fsrs-rs, 21 parameters); tests check the reference's published vectors.
//
//   retrievability   R(t, S) = (1 + F·t/S)^(−w20),  F = 0.9^(−1/w20) − 1,  t in whole days
//   interval         I(S) = S/F · (r^(−1/w20) − 1), rounded to whole days, 1..maximumIntervalDays
//   first answer     S0(G) = w[G−1];  D0(G) = w4 − e^(w5·(G−1)) + 1
//   difficulty       D' = w7·D0(Easy) + (1−w7)·(D + (10−D)/9 · (−w6·(G−3))), clamped to 1..10
//   recall (G ≥ 2)   S' = S·(1 + e^w8·(11−D)·S^(−w9)·(e^(w10·(1−R)) − 1)·[w15 if Hard]·[w16 if Easy])
//   lapse (Again)    S' = min(w11·D^(−w12)·((S+1)^w13 − 1)·e^(w14·(1−R)),  S / e^(w17·w18))
//   same day (t < 1) S' = S · e^(w17·(G−3+w18)) · S^(−w19)  (the factor at least 1 for Good/Easy)
//
// Phases: a structure is New until its first answer, then Learning (short steps, default 1 and
// 10 minutes) until it graduates to Review (intervals in days); Again in Review sends it to
// Relearning (default one 10-minute step) and back.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "volume/error.h"

namespace at::lessons {

using UnixSeconds = std::int64_t;

// The four FSRS grades. lessons::ratingFor maps a graded answer to one.
enum class Rating { Again = 1, Hard = 2, Good = 3, Easy = 4 };
const char* toString(Rating rating);  // "again", "hard", "good", "easy"
Result<Rating> parseRating(const std::string& text);

enum class MemoryPhase { New, Learning, Review, Relearning };
const char* toString(MemoryPhase phase);  // "new", "learning", "review", "relearning"
Result<MemoryPhase> parseMemoryPhase(const std::string& text);

inline constexpr std::size_t kFsrsParameterCount = 21;
// py-fsrs / fsrs-rs FSRS-6 defaults (w0..w20).
inline constexpr std::array<double, kFsrsParameterCount> kFsrs6DefaultWeights{
    0.212,  1.2931, 2.3065, 8.2956, 6.4133, 0.8334, 3.0194, 0.001,  1.8722, 0.1666, 0.796,
    1.4835, 0.0614, 0.2629, 1.6483, 0.6014, 1.8729, 0.5425, 0.0912, 0.0658, 0.1542};

struct FsrsParameters {
  std::array<double, kFsrsParameterCount> w = kFsrs6DefaultWeights;
  double desiredRetention = 0.9;                          // in (0, 1)
  std::vector<UnixSeconds> learningSteps{60, 600};        // seconds; empty = straight to Review
  std::vector<UnixSeconds> relearningSteps{600};          // seconds; empty = stay in Review
  int maximumIntervalDays = 36500;
  // Spread Review intervals of 3 days or more by a few percent (the reference's fuzz ranges) so
  // that structures learned together do not all fall due on the same day.
  bool enableFuzz = false;
};

// Error naming the first parameter outside the reference implementation's bounds.
Status validate(const FsrsParameters& parameters);

// One student's memory of one structure (the reference's "card").
struct MemoryState {
  MemoryPhase phase = MemoryPhase::New;
  int step = 0;                 // Learning/Relearning: index into the steps
  double stability = 0;         // days; 0 while New
  double difficulty = 0;        // 1..10; 0 while New
  UnixSeconds due = 0;          // next review at or after this time
  UnixSeconds lastReview = 0;   // time of the last answer; 0 while New
  int reviews = 0;              // answers so far
  int lapses = 0;               // Again in Review so far
};

class Fsrs {
 public:
  // `parameters` must pass validate() (asserted).
  explicit Fsrs(FsrsParameters parameters = {});
  const FsrsParameters& parameters() const { return parameters_; }

  // The state after answering with `rating` at `at` (>= state.lastReview). `fuzz` in [0, 1) picks
  // the spread interval when fuzzing is on; callers pass a value derived from the student and
  // structure so that replays give the same schedule.
  MemoryState review(const MemoryState& state, Rating rating, UnixSeconds at, double fuzz = 0.5) const;

  // Predicted probability of recall at `at` (0 while New).
  double retrievability(const MemoryState& state, UnixSeconds at) const;

  // Whole days between two times, as the reference counts them (floor of the difference, >= 0).
  static int elapsedDays(UnixSeconds from, UnixSeconds to);

  // The formulas of the header comment, for tests and for the migration's documentation.
  double initialStability(Rating rating) const;
  double initialDifficulty(Rating rating, bool clamp = true) const;
  int nextIntervalDays(double stability) const;
  double forgettingCurve(double elapsedDays, double stability) const;
  double nextDifficulty(double difficulty, Rating rating) const;
  double shortTermStability(double stability, Rating rating) const;
  double nextStability(double difficulty, double stability, double retrievability, Rating rating) const;
  int fuzzedIntervalDays(int days, double fuzz) const;

 private:
  FsrsParameters parameters_;
  double decay_ = 0;   // −w20
  double factor_ = 0;  // 0.9^(1/decay) − 1
};

}  // namespace at::lessons
