// FOR TESTS ONLY: the lessons/ repository interfaces over plain containers, so that the engine can
// be tested without db/. The product uses db/'s SQLite implementation. `failNextRecord` simulates
// a storage failure of the next recordAnswer or recordReviewAnswer (nothing is stored).
#pragma once

#include <algorithm>
#include <map>

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
  bool failNextRecord = false;

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
    progressMap[{record.progress.userId, record.progress.structureId}] = record.progress;
    std::int64_t userId = 0;
    for (const auto& a : attemptList) {
      if (a.id == r.attemptId) userId = a.userId;
    }
    abilities[userId] = record.abilityAfter;
    difficulties[r.questionId] = record.difficultyAfter;
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
    progressMap[{record.progress.userId, record.progress.structureId}] = record.progress;
    abilities[r.userId] = record.abilityAfter;
    difficulties[r.questionId] = record.difficultyAfter;
    return r.id;
  }
  Result<std::vector<lessons::ReviewResponse>> reviewResponses(std::int64_t userId) override {
    std::vector<lessons::ReviewResponse> out;
    for (const auto& r : reviewList) {
      if (r.userId == userId) out.push_back(r);
    }
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
