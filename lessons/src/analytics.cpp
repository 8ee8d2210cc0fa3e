#include "lessons/analytics.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "quiz/elo.h"

namespace at::lessons {

double uncertaintyFactor(int answersSoFar) { return 1.0 / (1.0 + 0.05 * double(answersSoFar)); }

namespace {

std::vector<QuestionStats> questionStats(const AnalyticsInput& in) {
  std::map<std::string, QuestionStats> byId;
  for (const Lesson& lesson : in.course.lessons)
    for (const Step& step : lesson.steps)
      if (step.kind == StepKind::Question) {
        QuestionStats q;
        q.questionId = step.question.id;
        q.lessonId = lesson.id;
        q.structureId = step.question.target;
        q.kind = quiz::toString(step.question.kind);
        q.initialDifficulty = q.difficulty = step.question.difficulty;
        byId[q.questionId] = q;
      }
  // Exam items ("<exam id>.<kind>.<structure>") appear as they were answered.
  for (const ClassAnswer& a : in.answers) {
    if (byId.count(a.questionId)) continue;
    for (const ExamSpec& exam : in.course.exams) {
      const std::string prefix = exam.id + ".";
      if (a.questionId.rfind(prefix, 0) != 0) continue;
      QuestionStats q;
      q.questionId = a.questionId;
      q.lessonId = exam.id;
      q.structureId = a.structureId;
      const std::string rest = a.questionId.substr(prefix.size());
      q.kind = rest.substr(0, rest.find('.'));
      byId[q.questionId] = q;
    }
  }

  // The Elo replay over the class's answers in time order.
  std::vector<const ClassAnswer*> ordered;
  for (const ClassAnswer& a : in.answers)
    if (byId.count(a.questionId)) ordered.push_back(&a);
  std::sort(ordered.begin(), ordered.end(), [](const ClassAnswer* x, const ClassAnswer* y) {
    return x->answeredAt != y->answeredAt ? x->answeredAt < y->answeredAt : x->order < y->order;
  });
  std::map<std::int64_t, double> ability;
  std::map<std::int64_t, int> answeredByStudent;
  std::map<std::string, int> answeredByQuestion;
  for (const ClassAnswer* a : ordered) {
    QuestionStats& q = byId[a->questionId];
    double& theta = ability.try_emplace(a->userId, quiz::kDefaultAbility).first->second;
    const double expected = quiz::expectedScore(theta, q.difficulty);
    const double surprise = a->score - expected;
    theta += kAnalyticsEloK * uncertaintyFactor(answeredByStudent[a->userId]++) * surprise;
    q.difficulty -= kAnalyticsEloK * uncertaintyFactor(answeredByQuestion[a->questionId]++) * surprise;
    ++q.answers;
    q.correct += a->correct ? 1 : 0;
  }
  std::vector<QuestionStats> out;
  for (auto& [id, q] : byId) {
    q.correctShare = q.answers ? double(q.correct) / q.answers : 0;
    out.push_back(q);
  }
  std::sort(out.begin(), out.end(), [](const QuestionStats& a, const QuestionStats& b) {
    return a.difficulty != b.difficulty ? a.difficulty > b.difficulty : a.questionId < b.questionId;
  });
  return out;
}

std::vector<StructureStats> structureStats(const AnalyticsInput& in, const std::set<std::int64_t>& classIds,
                                           UnixSeconds now, const Fsrs& fsrs) {
  std::map<std::string, StructureStats> byId;
  const auto entry = [&](const std::string& id) -> StructureStats& {
    StructureStats& s = byId[id];
    if (s.structureId.empty()) {
      s.structureId = id;
      s.name = id;
      for (const Structure& st : in.structures)
        if (st.id == id && !st.displayName.empty()) s.name = st.displayName;
    }
    return s;
  };
  for (const ClassAnswer& a : in.answers) {
    StructureStats& s = entry(a.structureId);
    ++s.answers;
    s.correct += a.correct ? 1 : 0;
  }
  for (const StructureProgress& p : in.memories) {
    if (!classIds.count(p.userId) || p.memory.phase == MemoryPhase::New || !byId.count(p.structureId)) continue;
    StructureStats& s = byId[p.structureId];
    ++s.students;
    s.meanDifficulty += p.memory.difficulty;
    s.meanRecall += fsrs.retrievability(p.memory, now);
  }
  std::vector<StructureStats> out;
  for (auto& [id, s] : byId) {
    s.correctShare = s.answers ? double(s.correct) / s.answers : 0;
    if (s.students) {
      s.meanDifficulty /= s.students;
      s.meanRecall /= s.students;
    }
    out.push_back(s);
  }
  std::sort(out.begin(), out.end(), [](const StructureStats& a, const StructureStats& b) {
    if (a.correctShare != b.correctShare) return a.correctShare < b.correctShare;
    if (a.meanDifficulty != b.meanDifficulty) return a.meanDifficulty > b.meanDifficulty;
    return a.structureId < b.structureId;
  });
  return out;
}

}  // namespace

ClassAnalytics computeAnalytics(const AnalyticsInput& in, UnixSeconds now, const Fsrs& fsrs) {
  ClassAnalytics r;
  r.courseId = in.course.id;
  r.classSize = int(in.students.size());
  std::set<std::int64_t> classIds;
  for (const User& u : in.students) classIds.insert(u.id);
  AnalyticsInput ofClass = in;  // answers of students outside the class do not count
  std::erase_if(ofClass.answers, [&](const ClassAnswer& a) { return !classIds.count(a.userId); });
  r.answers = int(ofClass.answers.size());
  r.questions = questionStats(ofClass);
  r.structures = structureStats(ofClass, classIds, now, fsrs);

  for (const Lesson& lesson : in.course.lessons) {
    LessonCompletion c;
    c.lessonId = lesson.id;
    c.title = lesson.title;
    std::map<std::int64_t, double> best;  // of the ends with a known score
    std::set<std::int64_t> started, finished;
    for (const Attempt& a : in.attempts) {
      if (a.lessonId != lesson.id || !classIds.count(a.userId)) continue;
      started.insert(a.userId);
      if (!a.finishedAt) continue;
      finished.insert(a.userId);
      if (a.scoreKnown) best[a.userId] = std::max(best.count(a.userId) ? best[a.userId] : 0.0, a.score);
    }
    c.started = int(started.size());
    c.finished = int(finished.size());
    c.scoresUnknown = int(finished.size() - best.size());
    c.completion = r.classSize ? double(c.finished) / r.classSize : 0;
    if (!best.empty()) {
      double sum = 0;
      for (const auto& [user, score] : best) sum += score;
      c.meanBestScore = sum / double(best.size());
    }
    r.lessons.push_back(c);
  }

  for (const User& u : in.students) {
    StudentRecall s;
    s.userId = u.id;
    s.name = u.name;
    s.group = u.group;
    std::vector<Attempt> attempts;
    for (const Attempt& a : in.attempts)
      if (a.userId == u.id) attempts.push_back(a);
    std::set<std::string> finished;
    for (const Attempt& a : attempts)
      if (a.finishedAt) finished.insert(a.lessonId);
    for (const Lesson& lesson : in.course.lessons) s.lessonsFinished += finished.count(lesson.id) ? 1 : 0;
    std::vector<StructureProgress> memories;
    for (const StructureProgress& p : in.memories)
      if (p.userId == u.id) memories.push_back(p);
    const auto taught = taughtStructureIds(in.course, attempts, memories);
    s.taught = int(taught.size());
    double sum = 0;
    for (const StructureProgress& p : memories) {
      if (!std::binary_search(taught.begin(), taught.end(), p.structureId)) continue;
      const double recall = fsrs.retrievability(p.memory, now);
      sum += recall;
      if (p.memory.due <= now) ++s.due;
      if (s.weakestStructure.empty() || recall < s.weakestRecall ||
          (recall == s.weakestRecall && p.structureId < s.weakestStructure)) {
        s.weakestStructure = p.structureId;
        s.weakestRecall = recall;
      }
    }
    if (s.taught) s.meanRecall = sum / s.taught;
    const ExamAttempt* latest = nullptr;
    for (const ExamAttempt& e : in.examAttempts)
      if (e.userId == u.id && e.finishedAt && (!latest || *e.finishedAt > *latest->finishedAt ||
                                               (*e.finishedAt == *latest->finishedAt && e.id > latest->id)))
        latest = &e;
    if (latest) s.examScore = latest->score;
    r.students.push_back(s);
  }
  std::sort(r.students.begin(), r.students.end(), [](const StudentRecall& a, const StudentRecall& b) {
    const double x = a.meanRecall.value_or(2), y = b.meanRecall.value_or(2);
    return x != y ? x < y : a.name < b.name;
  });

  for (const ExamSpec& exam : in.course.exams) {
    ExamStats e;
    e.examId = exam.id;
    e.title = exam.title;
    double sum = 0;
    int passed = 0;
    for (const ExamAttempt& a : in.examAttempts) {
      if (a.examId != exam.id || !classIds.count(a.userId)) continue;
      ++e.attempts;
      if (!a.finishedAt) continue;
      ++e.finished;
      sum += a.score;
      passed += a.passed.value_or(false) ? 1 : 0;
    }
    if (e.finished) {
      e.meanScore = sum / e.finished;
      if (exam.passScore) e.passRate = double(passed) / e.finished;
    }
    r.exams.push_back(e);
  }
  return r;
}

std::vector<QuestionStats> mostMissed(const ClassAnalytics& analytics, std::size_t limit) {
  std::vector<QuestionStats> missed;
  for (const QuestionStats& q : analytics.questions)
    if (q.answers > q.correct) missed.push_back(q);
  std::sort(missed.begin(), missed.end(), [](const QuestionStats& a, const QuestionStats& b) {
    const int ma = a.answers - a.correct, mb = b.answers - b.correct;
    if (ma != mb) return ma > mb;
    if (a.correctShare != b.correctShare) return a.correctShare < b.correctShare;
    return a.questionId < b.questionId;
  });
  if (missed.size() > limit) missed.resize(limit);
  return missed;
}

}  // namespace at::lessons
