// The Class analytics window (instructors): draws AnalyticsController's figures — the structures
// by error rate, the items most missed, each student's progress, lesson completion and exams — as
// tables with bars, and calls its commands (the UI script's analytics action calls the same).
#include <imgui.h>

#include <cstdio>
#include <ctime>
#include <utility>

#include "core/strings.h"
#include "ui/list_rows.h"
#include "ui/panels.h"
#include "core/printable_text.h"

namespace at::app {

namespace {

const ImVec4 kErrorColour(0.85f, 0.35f, 0.3f, 1), kRecallColour(0.3f, 0.65f, 0.9f, 1), kDoneColour(0.35f, 0.75f, 0.4f, 1);

std::string percent(double share) {
  char t[16];
  std::snprintf(t, sizeof t, "%.0f%%", 100 * share);
  return t;
}

// A bar of `share` (0..1) filling the column, labelled with `label`.
void bar(double share, const ImVec4& colour, const std::string& label) {
  ImGui::PushStyleColor(ImGuiCol_PlotHistogram, colour);
  ImGui::ProgressBar(float(std::clamp(share, 0.0, 1.0)), ImVec2(-1, 0), label.c_str());
  ImGui::PopStyleColor();
}

// Wrapped text of a table cell.
void cellText(const std::string& text) {
  ImGui::PushTextWrapPos(0);
  ImGui::TextUnformatted(printableUiText(text).c_str());
  ImGui::PopTextWrapPos();
}

bool beginTable(const char* id, int columns) {
  return ImGui::BeginTable(id, columns,
                           ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerH | ImGuiTableFlags_ScrollY |
                               ImGuiTableFlags_SizingStretchProp,
                           ImVec2(0, ImGui::GetContentRegionAvail().y));
}

void headers(std::initializer_list<std::pair<const char*, float>> columns) {
  ImGui::TableSetupScrollFreeze(0, 1);
  for (const auto& [name, weight] : columns) ImGui::TableSetupColumn(name, ImGuiTableColumnFlags_WidthStretch, weight);
  ImGui::TableHeadersRow();
}

}  // namespace

void AnalyticsPanel::draw(AnalyticsController& analytics, float x, float y, float width, float height) {
  if (!analytics.windowOpen) {
    courses_.reset();
    return;
  }
  if (!courses_) {  // read once each time the window opens
    auto courses = analytics.courses();
    courses_ = courses ? *courses : std::vector<AnalyticsController::CourseChoice>{};
    error_ = courses ? "" : courses.error().message;
    if (!analytics.loaded() && !courses_->empty()) report(analytics.load(courses_->front().id));
  }
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  ImGui::SetNextWindowSize(ImVec2(width, height), ImGuiCond_Appearing);
  if (!ImGui::Begin("Class analytics", &analytics.windowOpen)) {
    ImGui::End();
    return;
  }
  const float em = ImGui::GetFontSize();
  // Course and group.
  const std::string current = analytics.loaded() ? analytics.course().title : "(choose a course)";
  ImGui::SetNextItemWidth(em * 26);
  if (ImGui::BeginCombo("Course", printableUiText(current).c_str())) {
    for (int i = 0; i < int(courses_->size()); ++i)
      if (const auto& c = (*courses_)[std::size_t(i)];
          listRowSelectable(i, c.title, analytics.loaded() && analytics.course().id == c.id))
        report(analytics.load(c.id));
    ImGui::EndCombo();
  }
  if (analytics.loaded() && !analytics.groups().empty()) {
    ImGui::SameLine();
    ImGui::SetNextItemWidth(em * 10);
    const std::string group = analytics.group().value_or("All students");
    if (ImGui::BeginCombo("Group", printableUiText(group).c_str())) {
      if (ImGui::Selectable("All students", !analytics.group())) report(analytics.load(analytics.course().id));
      for (const std::string& g : analytics.groups())
        if (ImGui::Selectable(printableUiText(g).c_str(), analytics.group() == g)) report(analytics.load(analytics.course().id, g));
      ImGui::EndCombo();
    }
  }
  if (analytics.loaded()) {
    ImGui::SameLine();
    if (ImGui::Button("Refresh")) report(analytics.refresh());
  }
  if (!error_.empty()) ImGui::TextColored(kErrorColour, "%s", error_.c_str());
  if (!analytics.loaded()) {
    ImGui::TextWrapped("No course to show: the database has no courses yet.");
    ImGui::End();
    return;
  }
  const lessons::ClassAnalytics& a = analytics.analytics();
  char when[32] = "";
  const std::time_t at = std::time_t(analytics.computedAt());
  std::tm local{};
  if (localtime_r(&at, &local)) std::strftime(when, sizeof when, "%Y-%m-%d %H:%M", &local);
  ImGui::TextDisabled("Class of %s, %s recorded (as of %s).", str::countOf(a.classSize, "student").c_str(),
                      str::countOf(a.answers, "answer").c_str(), when);
  if (a.classSize == 0) {
    ImGui::TextWrapped("No students in this class yet: students appear here once they have an account "
                       "(anatomy-tutor play --user NAME --new-user, or the desktop's --user).");
    ImGui::End();
    return;
  }
  using Tab = AnalyticsController::Tab;
  const std::optional<Tab> requested = std::exchange(analytics.requestedTab, std::nullopt);
  const auto tab = [&](const char* label, Tab which) {
    return ImGui::BeginTabItem(label, nullptr, requested == which ? ImGuiTabItemFlags_SetSelected : 0);
  };
  if (ImGui::BeginTabBar("analytics_tabs")) {
    if (tab("Structures", Tab::Structures)) {
      drawStructures(analytics);
      ImGui::EndTabItem();
    }
    if (tab("Most missed", Tab::MostMissed)) {
      drawMissed(analytics);
      ImGui::EndTabItem();
    }
    if (tab("Students", Tab::Students)) {
      drawStudents(analytics);
      ImGui::EndTabItem();
    }
    if (tab("Lessons and exams", Tab::Lessons)) {
      drawLessons(analytics);
      ImGui::EndTabItem();
    }
    ImGui::EndTabBar();
  }
  ImGui::End();
}

void AnalyticsPanel::report(const Status& st) { error_ = st ? "" : st.error().message; }

void AnalyticsPanel::drawStructures(const AnalyticsController& analytics) {
  ImGui::TextWrapped("Error rate: the share of the class's answers about the structure that were not right "
                     "(lessons, reviews and exams). Recall: the chance, predicted now, that a student who was "
                     "taught it still knows it (mean over those students).");
  if (!beginTable("structures", 4)) return;
  headers({{"Structure", 3}, {"Error rate", 4}, {"Answers", 1.3f}, {"Recall now", 3}});
  for (const lessons::StructureStats& s : analytics.analytics().structures) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    cellText(s.name);
    ImGui::TableNextColumn();
    bar(1 - s.correctShare, kErrorColour, percent(1 - s.correctShare));
    ImGui::TableNextColumn();
    ImGui::Text("%d", s.answers);
    ImGui::TableNextColumn();
    if (s.students) bar(s.meanRecall, kRecallColour, percent(s.meanRecall) + " of " + str::countOf(s.students, "student"));
    else ImGui::TextDisabled("not taught yet");
  }
  ImGui::EndTable();
}

void AnalyticsPanel::drawMissed(const AnalyticsController& analytics) {
  ImGui::TextWrapped("The questions the class got wrong most often. Difficulty: 1500 is an average question, "
                     "higher is harder (estimated from who answered it and how).");
  if (!beginTable("missed", 5)) return;
  headers({{"Question", 6}, {"Lesson", 2.5f}, {"Missed", 1.6f}, {"Error rate", 2.5f}, {"Difficulty", 1.5f}});
  for (const lessons::QuestionStats& q : analytics.mostMissed(30)) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    cellText(analytics.questionText(q));
    ImGui::TableNextColumn();
    cellText(analytics.titleOf(q.lessonId));
    ImGui::TableNextColumn();
    ImGui::Text("%d of %d", q.answers - q.correct, q.answers);
    ImGui::TableNextColumn();
    bar(1 - q.correctShare, kErrorColour, percent(1 - q.correctShare));
    ImGui::TableNextColumn();
    ImGui::Text("%.0f", q.difficulty);
  }
  ImGui::EndTable();
}

void AnalyticsPanel::drawStudents(const AnalyticsController& analytics) {
  ImGui::TextWrapped("Weakest predicted recall first. Recall: the mean chance, predicted now, that the student "
                     "still knows the structures taught so far; due: structures waiting for a review.");
  if (!beginTable("students", 6)) return;
  headers({{"Student", 2.5f}, {"Lessons finished", 3}, {"Recall now", 3}, {"Due", 1}, {"Weakest", 2.8f}, {"Exam", 1.2f}});
  const int lessons = int(analytics.course().lessons.size());
  for (const lessons::StudentRecall& s : analytics.analytics().students) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    cellText(s.group.empty() ? s.name : s.name + " (" + s.group + ")");
    ImGui::TableNextColumn();
    bar(lessons ? double(s.lessonsFinished) / lessons : 0, kDoneColour, std::to_string(s.lessonsFinished) + " of " + std::to_string(lessons));
    ImGui::TableNextColumn();
    if (s.meanRecall) bar(*s.meanRecall, kRecallColour, percent(*s.meanRecall));
    else ImGui::TextDisabled("nothing taught yet");
    ImGui::TableNextColumn();
    ImGui::Text("%d", s.due);
    ImGui::TableNextColumn();
    if (!s.weakestStructure.empty()) cellText(analytics.displayName(s.weakestStructure) + " (" + percent(s.weakestRecall) + ")");
    ImGui::TableNextColumn();
    if (s.examScore) ImGui::TextUnformatted(percent(*s.examScore).c_str());
    else ImGui::TextDisabled("–");
  }
  ImGui::EndTable();
}

void AnalyticsPanel::drawLessons(const AnalyticsController& analytics) {
  const lessons::ClassAnalytics& a = analytics.analytics();
  ImGui::TextWrapped("Completion: the share of the class that finished the lesson; best score: the mean of "
                     "each finishing student's best attempt.");
  const float tableHeight = ImGui::GetTextLineHeightWithSpacing() * float(a.lessons.size() + 2);
  if (ImGui::BeginTable("lessons", 4, ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerH | ImGuiTableFlags_SizingStretchProp,
                        ImVec2(0, tableHeight))) {
    headers({{"Lesson", 3}, {"Completion", 4}, {"Started", 1.2f}, {"Best score", 1.5f}});
    for (const lessons::LessonCompletion& l : a.lessons) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      cellText(l.title);
      ImGui::TableNextColumn();
      bar(l.completion, kDoneColour, std::to_string(l.finished) + " of " + std::to_string(a.classSize) + " (" + percent(l.completion) + ")");
      ImGui::TableNextColumn();
      ImGui::Text("%d", l.started);
      ImGui::TableNextColumn();
      if (l.meanBestScore) ImGui::TextUnformatted(percent(*l.meanBestScore).c_str());
      else ImGui::TextDisabled("–");
      if (l.scoresUnknown) {
        ImGui::SameLine();
        ImGui::TextDisabled("(%d waiting for keys)", l.scoresUnknown);
      }
    }
    ImGui::EndTable();
  }
  if (a.exams.empty()) return;
  ImGui::Spacing();
  ImGui::TextUnformatted("Exams");
  for (const lessons::ExamStats& e : a.exams) {
    ImGui::BulletText("%s: %s, %d finished", printableUiText(e.title).c_str(), str::countOf(e.attempts, "attempt").c_str(), e.finished);
    if (e.meanScore) {
      ImGui::SameLine();
      ImGui::Text("- mean score %s", percent(*e.meanScore).c_str());
    }
    if (e.passRate) {
      ImGui::SameLine();
      ImGui::Text("- %s passed", percent(*e.passRate).c_str());
    }
  }
}

}  // namespace at::app
