// FOR TESTS ONLY: the lessons/ repository interfaces over plain containers, so that the engine can
// be tested without db/. The product uses db/'s SQLite implementation. `failNextRecord` simulates
// a storage failure of the next recordAnswer or recordReviewAnswer (nothing is stored).
#pragma once

#include <algorithm>
#include <map>

#include "lessons/exam.h"
#include "lessons/repositories.h"
#include "quiz/keys.h"

namespace at::test {

class InMemoryCurriculum final : public lessons::CurriculumRepository {
 public:
  std::vector<lessons::Course> courseList;
  std::map<std::string, std::vector<Structure>> datasets;

  Result<std::vector<lessons::Course>> courses() override { return courseList; }
  Result<lessons::Course> course(const std::string& id) override {
    for (const auto& c : courseList) {
      if (c.id == id) return c;
    }
    return fail("unknown course '" + id + "'");
  }
  Result<lessons::Lesson> lesson(const std::string& id) override {
    for (const auto& c : courseList) {
      for (const auto& l : c.lessons) {
        if (l.id == id) return l;
      }
    }
    return fail("unknown lesson '" + id + "'");
  }
  Result<quiz::Question> question(const std::string& id) override {
    for (const auto& c : courseList) {
      for (const auto& l : c.lessons) {
        for (const auto& s : l.steps) {
          if (s.kind == lessons::StepKind::Question && s.question.id == id) return s.question;
        }
      }
    }
    return fail("unknown question '" + id + "'");
  }
  Result<std::vector<Structure>> structures(const std::string& datasetId) override {
    const auto it = datasets.find(datasetId);
    if (it == datasets.end()) return fail("unknown dataset '" + datasetId + "'");
    return it->second;
  }
};

class InMemoryProgress final : public lessons::ProgressRepository {
 public:
  std::vector<lessons::Attempt> attemptList;
  std::vector<lessons::Response> responseList;
  std::vector<lessons::ReviewResponse> reviewList;
  std::map<std::pair<std::int64_t, std::string>, lessons::StructureProgress> progressMap;
  std::map<std::int64_t, double> abilities;
  std::map<std::string, double> difficulties;
  std::vector<lessons::ReviewLogEntry> log;
  bool failNextRecord = false;

  // As db/ writes the review log: one entry per graded answer, before → after.
  void logAnswer(std::int64_t userId, const lessons::GradedAnswer& answer, const lessons::LearnerUpdate& u,
                 lessons::AnswerSource source) {
    lessons::ReviewLogEntry e;
    e.id = std::int64_t(log.size()) + 1;
    e.userId = userId;
    e.structureId = u.progress.structureId;
    e.questionId = answer.questionId;
    e.source = source;
    e.reviewedAt = answer.answeredAt;
    e.rating = u.rating;
    e.correct = answer.correct;
    e.score = answer.score;
    e.latencyMs = answer.latencyMs;
    e.phaseBefore = u.memoryBefore.phase;
    e.elapsedDays = u.memoryBefore.phase == lessons::MemoryPhase::New
                        ? -1
                        : lessons::Fsrs::elapsedDays(u.memoryBefore.lastReview, answer.answeredAt);
    e.after = u.progress.memory;
    log.push_back(e);
  }
  void applyUpdate(std::int64_t userId, const std::string& questionId, const lessons::LearnerUpdate& u) {
    progressMap[{u.progress.userId, u.progress.structureId}] = u.progress;
    abilities[userId] = u.abilityAfter;
    difficulties[questionId] = u.difficultyAfter;
  }

  Result<std::optional<lessons::Attempt>> openAttempt(std::int64_t userId, const std::string& lessonId) override {
    std::optional<lessons::Attempt> open;
    for (const auto& a : attemptList) {
      if (a.userId == userId && a.lessonId == lessonId && !a.finishedAt) open = a;
    }
    return open;
  }
  Result<lessons::Attempt> startAttempt(std::int64_t userId, const std::string& lessonId, lessons::LessonMode mode,
                                        lessons::UnixSeconds startedAt) override {
    lessons::Attempt a;
    a.id = std::int64_t(attemptList.size()) + 1;
    a.userId = userId;
    a.lessonId = lessonId;
    a.mode = mode;
    a.startedAt = startedAt;
    attemptList.push_back(a);
    return a;
  }
  Status finishAttempt(std::int64_t attemptId, lessons::UnixSeconds finishedAt, double score) override {
    for (auto& a : attemptList) {
      if (a.id == attemptId) {
        a.finishedAt = finishedAt;
        a.score = score;
        return {};
      }
    }
    return fail("unknown attempt " + std::to_string(attemptId));
  }
  Result<std::vector<lessons::Attempt>> attempts(std::int64_t userId) override {
    std::vector<lessons::Attempt> out;
    for (auto it = attemptList.rbegin(); it != attemptList.rend(); ++it)
      if (it->userId == userId) out.push_back(*it);
    return out;
  }
  Result<bool> hasFinished(std::int64_t userId, const std::string& lessonId) override {
    return std::any_of(attemptList.begin(), attemptList.end(), [&](const lessons::Attempt& a) {
      return a.userId == userId && a.lessonId == lessonId && a.finishedAt.has_value();
    });
  }
  Result<std::vector<lessons::Response>> responses(std::int64_t attemptId) override {
    std::vector<lessons::Response> out;
    for (const auto& r : responseList) {
      if (r.attemptId == attemptId) out.push_back(r);
    }
    return out;
  }
  Result<std::int64_t> recordAnswer(const lessons::AnswerRecord& record) override {
    if (failNextRecord) {
      failNextRecord = false;
      return fail("disk full");
    }
    lessons::Response r = record.response;
    r.id = std::int64_t(responseList.size()) + 1;
    responseList.push_back(r);
    std::int64_t userId = 0;
    for (const auto& a : attemptList) {
      if (a.id == r.attemptId) userId = a.userId;
    }
    applyUpdate(userId, r.questionId, record.update);
    logAnswer(userId, r, record.update, lessons::AnswerSource::Lesson);
    return r.id;
  }
  Result<std::int64_t> recordReviewAnswer(const lessons::ReviewRecord& record) override {
    if (failNextRecord) {
      failNextRecord = false;
      return fail("disk full");
    }
    lessons::ReviewResponse r = record.response;
    r.id = std::int64_t(reviewList.size()) + 1;
    reviewList.push_back(r);
    applyUpdate(r.userId, r.questionId, record.update);
    logAnswer(r.userId, r, record.update, lessons::AnswerSource::Review);
    return r.id;
  }
  Result<std::vector<lessons::ReviewResponse>> reviewResponses(std::int64_t userId) override {
    std::vector<lessons::ReviewResponse> out;
    for (const auto& r : reviewList) {
      if (r.userId == userId) out.push_back(r);
    }
    return out;
  }
  Result<std::vector<lessons::ReviewLogEntry>> reviewLog(std::int64_t userId) override {
    std::vector<lessons::ReviewLogEntry> out;
    for (const auto& e : log)
      if (e.userId == userId) out.push_back(e);
    return out;
  }
  Result<std::optional<lessons::StructureProgress>> progress(std::int64_t userId, const std::string& structureId) override {
    const auto it = progressMap.find({userId, structureId});
    if (it == progressMap.end()) return std::optional<lessons::StructureProgress>{};
    return std::optional<lessons::StructureProgress>(it->second);
  }
  Result<std::vector<lessons::StructureProgress>> allProgress(std::int64_t userId) override {
    std::vector<lessons::StructureProgress> out;
    for (const auto& [key, p] : progressMap) {
      if (key.first == userId) out.push_back(p);
    }
    return out;
  }
  Result<std::optional<double>> ability(std::int64_t userId) override {
    const auto it = abilities.find(userId);
    if (it == abilities.end()) return std::optional<double>{};
    return std::optional<double>(it->second);
  }
  Result<std::optional<double>> questionDifficulty(const std::string& questionId) override {
    const auto it = difficulties.find(questionId);
    if (it == difficulties.end()) return std::optional<double>{};
    return std::optional<double>(it->second);
  }
};

class InMemoryExams final : public lessons::ExamRepository {
 public:
  explicit InMemoryExams(InMemoryProgress& progress) : progress_(progress) {}
  std::vector<lessons::ExamAttempt> attemptList;
  std::map<std::int64_t, std::vector<lessons::ExamItem>> itemsByAttempt;
  bool failNextRecord = false;

  Result<std::optional<lessons::ExamAttempt>> openExamAttempt(std::int64_t userId, const std::string& examId) override {
    std::optional<lessons::ExamAttempt> open;
    for (const auto& a : attemptList)
      if (a.userId == userId && a.examId == examId && !a.finishedAt) open = a;
    return open;
  }
  Result<lessons::ExamAttempt> startExamAttempt(const lessons::ExamAttempt& attempt,
                                                std::vector<lessons::ExamItem>& items) override {
    lessons::ExamAttempt a = attempt;
    a.id = std::int64_t(attemptList.size()) + 1;
    for (auto& item : items) item.id = a.id * 1000 + item.position;
    attemptList.push_back(a);
    itemsByAttempt[a.id] = items;
    return a;
  }
  Result<std::vector<lessons::ExamItem>> examItems(std::int64_t attemptId) override { return itemsByAttempt[attemptId]; }
  Status recordExamAnswer(const lessons::ExamAnswerRecord& r) override {
    if (failNextRecord) {
      failNextRecord = false;
      return fail("disk full");
    }
    auto& items = itemsByAttempt[r.attemptId];
    if (r.position < 0 || r.position >= int(items.size()) || items[std::size_t(r.position)].answer)
      return fail("exam item already answered");
    auto& item = items[std::size_t(r.position)];
    item.answer = r.answer.answer;
    item.correct = r.answer.correct;
    item.score = r.answer.score;
    item.latencyMs = r.answer.latencyMs;
    item.answeredAt = r.answer.answeredAt;
    std::int64_t userId = 0;
    for (const auto& a : attemptList)
      if (a.id == r.attemptId) userId = a.userId;
    progress_.applyUpdate(userId, r.answer.questionId, r.update);
    progress_.logAnswer(userId, r.answer, r.update, lessons::AnswerSource::Exam);
    return {};
  }
  Status finishExamAttempt(std::int64_t attemptId, lessons::UnixSeconds finishedAt, double score,
                           std::optional<bool> passed) override {
    for (auto& a : attemptList)
      if (a.id == attemptId) {
        a.finishedAt = finishedAt;
        a.score = score;
        a.passed = passed;
        return {};
      }
    return fail("unknown exam attempt");
  }
  Result<std::vector<lessons::ExamAttempt>> examAttempts(std::int64_t userId) override {
    std::vector<lessons::ExamAttempt> out;
    for (auto it = attemptList.rbegin(); it != attemptList.rend(); ++it)
      if (it->userId == userId) out.push_back(*it);
    return out;
  }

 private:
  InMemoryProgress& progress_;
};

// Key facts given directly as tables: distances between structures, centroids, and a fixed list of
// structures along any path.
class TableKeyComputer final : public quiz::KeyComputer {
 public:
  std::vector<std::string> structureIds;
  std::map<std::string, quiz::StructureDistances> distances;
  std::vector<std::string> along;

  bool hasStructure(const std::string& id) const override {
    return std::find(structureIds.begin(), structureIds.end(), id) != structureIds.end();
  }
  Result<quiz::StructureDistances> distancesFrom(const std::string& id) override {
    const auto it = distances.find(id);
    if (it == distances.end()) return fail("no distances from '" + id + "'");
    return it->second;
  }
  Result<Vec3> centroidMm(const std::string& id) override { return Vec3{0, 0, 0}; }
  Result<std::vector<std::string>> structuresAlong(const Vec3&, const Vec3&) override { return along; }
};

}  // namespace at::test
