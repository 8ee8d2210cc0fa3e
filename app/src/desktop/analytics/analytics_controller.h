// The desktop's Class analytics window without drawing (ui/analytics_panel.cpp draws it; the UI
// script's analytics action drives the same commands): an instructor's view of one course's class,
// read from the learning session's database (db/analytics_store.h) and computed by
// lessons/analytics.h — the structures by error rate, the items most missed, each student's
// progress (lessons finished, predicted recall, reviews due, latest exam score), lesson completion
// and exam results. The figures are those of `anatomy-tutor analytics COURSE`, as of the moment
// they were loaded; Refresh reads the database again.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "learning_session.h"
#include "lessons/analytics.h"

namespace at::app {

class AnalyticsController {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  using Now = std::function<lessons::UnixSeconds()>;
  // `session` outlives the controller. `events` receives "analytics" after each load. `now`: the
  // clock predicted recall is computed at (default: the system's).
  AnalyticsController(LearningSession& session, EventSink events, Now now = {});

  bool windowOpen = false;
  // The window's tabs; the script may bring one to the front (the window takes the request once).
  enum class Tab { Structures, MostMissed, Students, Lessons };
  std::optional<Tab> requestedTab;
  static std::optional<Tab> parseTab(const std::string& name);  // "structures", "missed", "students", "lessons"

  struct CourseChoice {
    std::string id, title;
  };
  // The courses in the database, in its order.
  Result<std::vector<CourseChoice>> courses();

  // Reads the class of `courseId` — every student, or those of `group` — and computes its
  // analytics [analytics]. An error (unknown course, unreadable database) keeps what was shown.
  Status load(const std::string& courseId, const std::optional<std::string>& group = std::nullopt);
  // The same course and group again, with what was recorded since.
  Status refresh();

  bool loaded() const { return analytics_.has_value(); }
  // Valid when loaded().
  const lessons::ClassAnalytics& analytics() const { return *analytics_; }
  const lessons::Course& course() const { return course_; }
  const std::optional<std::string>& group() const { return group_; }
  // The groups of the course's whole class (non-empty ones, sorted), for choosing one.
  const std::vector<std::string>& groups() const { return groups_; }
  lessons::UnixSeconds computedAt() const { return computedAt_; }
  // The items most missed (lessons::mostMissed), at most `limit`.
  std::vector<lessons::QuestionStats> mostMissed(std::size_t limit) const;
  // A structure's display name in the course's dataset (its id when unknown).
  std::string displayName(const std::string& structureId) const;
  // What a question asks, for a table row: its prompt (lesson questions) or the exam item's kind
  // and structure ("exam: locate the cochlea").
  std::string questionText(const lessons::QuestionStats& q) const;
  // The title of a lesson or exam of the course (its id when unknown).
  std::string titleOf(const std::string& lessonOrExamId) const;
  // Bumped on every load.
  std::uint64_t revision() const { return revision_; }

 private:
  LearningSession& session_;
  EventSink events_;
  Now now_;
  std::optional<lessons::ClassAnalytics> analytics_;
  lessons::Course course_;
  std::vector<Structure> structures_;
  std::optional<std::string> group_;
  std::vector<std::string> groups_;
  lessons::UnixSeconds computedAt_ = 0;
  std::uint64_t revision_ = 0;
};

}  // namespace at::app
