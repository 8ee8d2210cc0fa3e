#include "lessons/fsrs.h"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace at::lessons {
namespace {

constexpr double kStabilityMin = 0.001;
constexpr double kDifficultyMin = 1.0;
constexpr double kDifficultyMax = 10.0;
constexpr UnixSeconds kDay = 86400;

// The reference's bounds on each parameter (what its optimiser may produce).
constexpr std::array<double, kFsrsParameterCount> kLower{
    kStabilityMin, kStabilityMin, kStabilityMin, kStabilityMin, 1.0, 0.001, 0.001, 0.001, 0.0, 0.0, 0.001,
    0.001,         0.001,         0.001,         0.0,           0.0, 1.0,   0.0,   0.0,   0.0, 0.1};
constexpr std::array<double, kFsrsParameterCount> kUpper{100.0, 100.0, 100.0, 100.0, 10.0, 4.0, 4.0,
                                                         0.75,  4.5,   0.8,   3.5,   5.0,  0.25, 0.9,
                                                         4.0,   1.0,   6.0,   2.0,   2.0,  0.8,  0.8};

double clampDifficulty(double d) { return std::clamp(d, kDifficultyMin, kDifficultyMax); }
double clampStability(double s) { return std::max(s, kStabilityMin); }
int grade(Rating rating) { return int(rating); }

}  // namespace

const char* toString(Rating rating) {
  switch (rating) {
    case Rating::Again: return "again";
    case Rating::Hard: return "hard";
    case Rating::Good: return "good";
    case Rating::Easy: return "easy";
  }
  return "?";
}

Result<Rating> parseRating(const std::string& text) {
  for (Rating r : {Rating::Again, Rating::Hard, Rating::Good, Rating::Easy})
    if (text == toString(r)) return r;
  return fail("unknown rating '" + text + "' (again, hard, good, easy)");
}

const char* toString(MemoryPhase phase) {
  switch (phase) {
    case MemoryPhase::New: return "new";
    case MemoryPhase::Learning: return "learning";
    case MemoryPhase::Review: return "review";
    case MemoryPhase::Relearning: return "relearning";
  }
  return "?";
}

Result<MemoryPhase> parseMemoryPhase(const std::string& text) {
  for (MemoryPhase p : {MemoryPhase::New, MemoryPhase::Learning, MemoryPhase::Review, MemoryPhase::Relearning})
    if (text == toString(p)) return p;
  return fail("unknown memory phase '" + text + "' (new, learning, review, relearning)");
}

Status validate(const FsrsParameters& p) {
  for (std::size_t i = 0; i < kFsrsParameterCount; ++i) {
    if (!(p.w[i] >= kLower[i] && p.w[i] <= kUpper[i]))
      return fail("FSRS parameter w" + std::to_string(i) + " = " + std::to_string(p.w[i]) + " is outside " +
                  std::to_string(kLower[i]) + ".." + std::to_string(kUpper[i]));
  }
  if (!(p.desiredRetention > 0 && p.desiredRetention < 1))
    return fail("FSRS desired retention must be in (0, 1), not " + std::to_string(p.desiredRetention));
  if (p.maximumIntervalDays < 1) return fail("FSRS maximum interval must be at least 1 day");
  for (const auto* steps : {&p.learningSteps, &p.relearningSteps})
    for (UnixSeconds s : *steps)
      if (s <= 0) return fail("FSRS (re)learning steps must be positive durations in seconds");
  return {};
}

Fsrs::Fsrs(FsrsParameters parameters) : parameters_(std::move(parameters)) {
  assert(validate(parameters_) && "Fsrs: parameters outside the reference bounds (call validate first)");
  decay_ = -parameters_.w[20];
  factor_ = std::pow(0.9, 1.0 / decay_) - 1.0;
}

int Fsrs::elapsedDays(UnixSeconds from, UnixSeconds to) {
  if (to <= from) return 0;
  return int((to - from) / kDay);
}

double Fsrs::initialStability(Rating rating) const { return clampStability(parameters_.w[std::size_t(grade(rating) - 1)]); }

double Fsrs::initialDifficulty(Rating rating, bool clamp) const {
  const double d = parameters_.w[4] - std::exp(parameters_.w[5] * (grade(rating) - 1)) + 1.0;
  return clamp ? clampDifficulty(d) : d;
}

int Fsrs::nextIntervalDays(double stability) const {
  const double days = stability / factor_ * (std::pow(parameters_.desiredRetention, 1.0 / decay_) - 1.0);
  // Ties round to even, as the reference (Python's round) does.
  const double rounded = std::nearbyint(days);
  return int(std::clamp(rounded, 1.0, double(parameters_.maximumIntervalDays)));
}

double Fsrs::forgettingCurve(double elapsedDays, double stability) const {
  return std::pow(1.0 + factor_ * elapsedDays / stability, decay_);
}

double Fsrs::nextDifficulty(double difficulty, Rating rating) const {
  const auto& w = parameters_.w;
  const double delta = -(w[6] * (grade(rating) - 3));
  const double damped = difficulty + (10.0 - difficulty) * delta / 9.0;
  return clampDifficulty(w[7] * initialDifficulty(Rating::Easy, false) + (1.0 - w[7]) * damped);
}

double Fsrs::shortTermStability(double stability, Rating rating) const {
  const auto& w = parameters_.w;
  double increase = std::exp(w[17] * (grade(rating) - 3 + w[18])) * std::pow(stability, -w[19]);
  if (rating == Rating::Good || rating == Rating::Easy) increase = std::max(increase, 1.0);
  return clampStability(stability * increase);
}

double Fsrs::nextStability(double difficulty, double stability, double retrievability, Rating rating) const {
  const auto& w = parameters_.w;
  double next = 0;
  if (rating == Rating::Again) {
    const double longTerm = w[11] * std::pow(difficulty, -w[12]) * (std::pow(stability + 1.0, w[13]) - 1.0) *
                            std::exp((1.0 - retrievability) * w[14]);
    const double shortTerm = stability / std::exp(w[17] * w[18]);
    next = std::min(longTerm, shortTerm);
  } else {
    const double hardPenalty = rating == Rating::Hard ? w[15] : 1.0;
    const double easyBonus = rating == Rating::Easy ? w[16] : 1.0;
    next = stability * (1.0 + std::exp(w[8]) * (11.0 - difficulty) * std::pow(stability, -w[9]) *
                                  (std::exp((1.0 - retrievability) * w[10]) - 1.0) * hardPenalty * easyBonus);
  }
  return clampStability(next);
}

int Fsrs::fuzzedIntervalDays(int days, double fuzz) const {
  if (days < 3) return days;  // the reference leaves intervals below 2.5 days alone
  struct Range {
    double start, end, factor;
  };
  constexpr Range ranges[] = {{2.5, 7.0, 0.15}, {7.0, 20.0, 0.1}, {20.0, 1e300, 0.05}};
  double delta = 1.0;
  for (const Range& r : ranges) delta += r.factor * std::max(std::min(double(days), r.end) - r.start, 0.0);
  int lo = int(std::nearbyint(days - delta));
  int hi = int(std::nearbyint(days + delta));
  lo = std::max(2, lo);
  hi = std::min(hi, parameters_.maximumIntervalDays);
  lo = std::min(lo, hi);
  const double u = std::clamp(fuzz, 0.0, std::nextafter(1.0, 0.0));
  // Uniform over lo..hi (the reference rounds u·(hi−lo+1)+lo, which can overshoot hi by one).
  return lo + int(std::floor(u * (hi - lo + 1)));
}

double Fsrs::retrievability(const MemoryState& state, UnixSeconds at) const {
  if (state.phase == MemoryPhase::New || state.stability <= 0) return 0;
  return forgettingCurve(elapsedDays(state.lastReview, at), state.stability);
}

MemoryState Fsrs::review(const MemoryState& before, Rating rating, UnixSeconds at, double fuzz) const {
  MemoryState s = before;
  const bool first = before.phase == MemoryPhase::New || before.stability <= 0;
  const int days = first ? 0 : elapsedDays(before.lastReview, at);

  // Memory state: first answer, same-day answer, or answer after a day or more.
  if (first) {
    s.phase = MemoryPhase::Learning;
    s.step = 0;
    s.stability = initialStability(rating);
    s.difficulty = initialDifficulty(rating);
  } else if (days < 1) {
    s.stability = shortTermStability(before.stability, rating);
    s.difficulty = nextDifficulty(before.difficulty, rating);
  } else {
    s.stability = nextStability(before.difficulty, before.stability, retrievability(before, at), rating);
    s.difficulty = nextDifficulty(before.difficulty, rating);
  }

  // Schedule: a short step, or graduation to Review with an interval in days.
  UnixSeconds wait = 0;
  bool inDays = false;
  const auto graduate = [&] {
    s.phase = MemoryPhase::Review;
    s.step = 0;
    inDays = true;
  };
  const auto stepThrough = [&](const std::vector<UnixSeconds>& steps) {
    if (steps.empty() || (s.step >= int(steps.size()) && rating != Rating::Again)) {
      graduate();
      return;
    }
    switch (rating) {
      case Rating::Again:
        s.step = 0;
        wait = steps[0];
        break;
      case Rating::Hard:  // the step stays
        if (s.step == 0 && steps.size() == 1) wait = steps[0] * 3 / 2;
        else if (s.step == 0) wait = (steps[0] + steps[1]) / 2;
        else wait = steps[std::size_t(s.step)];
        break;
      case Rating::Good:
        if (s.step + 1 >= int(steps.size())) {
          graduate();
        } else {
          ++s.step;
          wait = steps[std::size_t(s.step)];
        }
        break;
      case Rating::Easy:
        graduate();
        break;
    }
  };
  switch (s.phase) {
    case MemoryPhase::New:  // not reached: a first answer moved it to Learning
    case MemoryPhase::Learning:
      stepThrough(parameters_.learningSteps);
      break;
    case MemoryPhase::Relearning:
      stepThrough(parameters_.relearningSteps);
      break;
    case MemoryPhase::Review:
      if (rating == Rating::Again) {
        ++s.lapses;
        if (parameters_.relearningSteps.empty()) {
          inDays = true;
        } else {
          s.phase = MemoryPhase::Relearning;
          s.step = 0;
          wait = parameters_.relearningSteps[0];
        }
      } else {
        inDays = true;
      }
      break;
  }
  if (inDays) {
    int interval = nextIntervalDays(s.stability);
    if (parameters_.enableFuzz && s.phase == MemoryPhase::Review) interval = fuzzedIntervalDays(interval, fuzz);
    wait = UnixSeconds(interval) * kDay;
  }
  s.due = at + wait;
  s.lastReview = at;
  s.reviews = before.reviews + 1;
  return s;
}

}  // namespace at::lessons
