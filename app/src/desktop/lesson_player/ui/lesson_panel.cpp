#include <algorithm>
#include <cfloat>
#include <cstdio>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "class_practice.h"
#include "core/strings.h"
#include "lessons/repositories.h"
#include "ui/list_rows.h"
#include "ui/panels.h"
#include "volume/dataset_source.h"
#include "ui/widget_rects.h"
#include "core/printable_text.h"

namespace at::app {

namespace {
const ImVec4 kRight{0.5f, 1, 0.5f, 1}, kPartly{1, 0.8f, 0.35f, 1}, kWrong{1, 0.5f, 0.4f, 1}, kHeading{1, 0.75f, 0.3f, 1}, kQuestion{0.6f, 0.8f, 1, 1};

void wrappedColoured(const ImVec4& colour, const std::string& text) {
  ImGui::PushTextWrapPos(0);
  ImGui::TextColored(colour, "%s", printableUiText(text).c_str());
  ImGui::PopTextWrapPos();
}

// A note on what the class server does with a locate answer (class_practice.h), in brackets as the
// terminal prints it; noted as widget `name` with its words.
void classPracticeNote(const char* name, const std::string& note) {
  const std::string text = "(" + note + ")";
  wrappedColoured(kPartly, text);
  noteWidget(name, text);
}
}  // namespace

void LessonPanel::draw(LessonController& lessons, ExamController& exams, float height) {
  if (!ImGui::CollapsingHeader("Lessons", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::BeginChild("lessons", ImVec2(0, height), false);
  if (exams_.active(exams)) {
    exams_.draw(exams);
    if (!lessons.message().empty()) wrappedColoured(kWrong, lessons.message());
  } else if (auto title = lessons.preparing()) {
    ImGui::TextColored(kHeading, "%s", title->c_str());
    ImGui::TextDisabled("Preparing the lesson: computing its answer keys...");
  } else if (auto st = lessons.ready(); !st) {
    wrappedColoured(kWrong, st.error().message);
  } else {
    if (lessons.step()) {
      ImGui::TextDisabled("user: %s", printableUiText(lessons.user()->name).c_str());
    } else {
      if (!editingUser_) userEdit_ = lessons.user()->name;  // follows the user unless being typed
      ImGui::SetNextItemWidth(ImGui::GetFontSize() * 9);
      const bool entered = ImGui::InputText("##user", &userEdit_, ImGuiInputTextFlags_EnterReturnsTrue);
      editingUser_ = ImGui::IsItemActive();
      ImGui::SameLine();
      if ((ImGui::SmallButton("switch user") || entered) && userEdit_ != lessons.user()->name)
        if (auto s = lessons.switchUser(userEdit_); !s) lessons.report("user: " + s.error().message);
      if (ImGui::IsItemHovered()) ImGui::SetTooltip("progress is per user; `anatomy-tutor play --user NAME` shares it");
    }
    const LessonController::Asked* asked = lessons.asked();
    const bool reviewing = asked && asked->review;
    if (lessons.step() || lessons.finishedScore()) drawLesson(lessons);
    else if (reviewing) drawQuestion(lessons);
    else {
      drawLists(lessons);
      exams_.drawList(exams);
    }
    if (!lessons.message().empty()) wrappedColoured(kWrong, lessons.message());
    if (!lessons.step() && !lessons.finishedScore() && !reviewing) drawReview(lessons);
  }
  ImGui::EndChild();
}

void LessonPanel::drawLists(LessonController& lessons) {
  const auto& courses = lessons.courses();
  if (courses.empty()) {
    ImGui::TextDisabled("No course in the database.");
    return;
  }
  const lessons::Course& course = courses[std::size_t(lessons.courseIndex())];
  ImGui::SetNextItemWidth(-FLT_MIN);
  if (ImGui::BeginCombo("##course", printableUiText(course.title).c_str())) {
    for (int i = 0; i < int(courses.size()); ++i)
      if (listRowSelectable(i, courses[std::size_t(i)].title, i == lessons.courseIndex()) && i != lessons.courseIndex())
        if (auto st = lessons.selectCourse(i); !st) lessons.report(st.error().message);
    ImGui::EndCombo();
  }
  // The built-in phantom at any size has the same structures; other datasets only their own.
  const std::string& view = lessons.viewDataset();
  if (course.datasetId != view && !(isBuiltinDatasetName(course.datasetId) && isBuiltinDatasetName(view)))
    wrappedColoured(kWrong, "This course is on dataset '" + course.datasetId + "' but the view shows '" + view +
                                "': choose it in the Dataset menu above.");
  ImGui::Checkbox("quiz only", &lessons.quizOnly);
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Start lessons as a quiz: no teaching steps, no structure names");
  ImGui::PushTextWrapPos(0);
  for (const LessonController::LessonRow& row : lessons.rows()) {
    ImGui::PushID(row.id.c_str());
    const bool locked = !row.missing.empty();
    if (locked) ImGui::BeginDisabled();
    const char* action = row.open ? "Resume" : row.bestScore ? "Again" : "Start";
    if (ImGui::SmallButton(action))
      if (auto st = lessons.startLesson(row.id, lessons.quizOnly ? lessons::LessonMode::QuizOnly : lessons::LessonMode::Guided); !st)
        lessons.report(st.error().message);
    if (locked) ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::TextColored(locked ? ImVec4(0.6f, 0.6f, 0.6f, 1) : kHeading, "%s", printableUiText(row.title).c_str());
    if (ImGui::IsItemHovered() && !row.summary.empty()) ImGui::SetTooltip("%s", printableUiText(row.summary).c_str());
    if (locked) {
      std::string needs;
      for (const std::string& m : row.missing) needs += (needs.empty() ? "" : ", ") + m;
      ImGui::TextDisabled("  locked: finish %s first", printableUiText(needs).c_str());
    } else if (row.bestScore) {
      ImGui::TextColored(kRight, "  done, best score %.0f%%%s", 100 * *row.bestScore, row.open ? " (another attempt open)" : "");
    } else if (row.open) {
      ImGui::TextDisabled("  in progress");
    } else {
      ImGui::TextDisabled("  not started, %s", str::countOf(row.questions, "question").c_str());
    }
    ImGui::PopID();
  }
  ImGui::PopTextWrapPos();
}

void LessonPanel::drawLesson(LessonController& lessons) {
  if (!lessons.engine()) return;
  ImGui::TextColored(kHeading, "%s", printableUiText(lessons.engine()->lesson().title).c_str());
  if (auto score = lessons.finishedScore()) {
    ImGui::Text("Lesson finished: score %.0f%%", 100 * *score);
    if (ImGui::Button("Back to the lessons")) {
      lessons.backToLessons();
      return;
    }
    // The review: each question, the answer given and the right one; "show" puts its picture up.
    ImGui::PushTextWrapPos(0);
    const auto& review = lessons.lessonReview();
    for (int i = 0; i < int(review.size()); ++i) {
      const lessons::QuestionOutcome& o = review[std::size_t(i)];
      const bool right = o.grade && o.grade->correct;
      ImGui::PushID(i);
      ImGui::TextColored(right ? kRight : o.grade && o.grade->score > 0 ? kPartly : kWrong, "%d. %s", o.position,
                         o.prompt.c_str());
      ImGui::TextDisabled("you: %s  -  answer: %s", o.yourAnswer.empty() ? "(none)" : o.yourAnswer.c_str(),
                          o.rightAnswer.c_str());
      ImGui::SameLine();
      if (ImGui::SmallButton("show"))
        if (auto st = lessons.showReviewItem(i); !st) lessons.report(st.error().message);
      ImGui::SameLine();
      if (ImGui::SmallButton("slice"))
        if (auto st = lessons.showReviewItem(i, true); !st) lessons.report(st.error().message);
      ImGui::PopID();
    }
    ImGui::PopTextWrapPos();
    return;
  }
  const lessons::StepView& v = *lessons.step();
  ImGui::Text("step %d of %d", v.position, v.count);
  ImGui::SameLine();
  if (ImGui::SmallButton("Leave")) {  // answers are saved: Resume continues here
    lessons.leave();
    return;
  }
  if (v.kind == lessons::StepKind::Show) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(kHeading, "%s", printableUiText(v.title).c_str());
    if (v.labelsVisible && !v.structureName.empty() && v.structureName != v.title) ImGui::TextDisabled("%s", printableUiText(v.structureName).c_str());
    ImGui::TextUnformatted(printableUiText(v.text).c_str());
    ImGui::PopTextWrapPos();
  } else {
    drawQuestion(lessons);
  }
  const LessonController::Asked* asked = lessons.asked();
  const bool canGo = v.kind == lessons::StepKind::Show || (asked && asked->grade);
  if (v.position == 1) ImGui::BeginDisabled();
  if (ImGui::Button("Back"))
    if (auto st = lessons.back(); !st) lessons.report(st.error().message);
  if (v.position == 1) ImGui::EndDisabled();
  ImGui::SameLine();
  if (!canGo) ImGui::BeginDisabled();
  if (ImGui::Button(v.position == v.count ? "Finish" : "Next"))
    if (auto st = lessons.next(); !st) lessons.report(st.error().message);
  noteWidget("lesson_next");
  if (!canGo) ImGui::EndDisabled();
  // Once an answer is graded, its feedback and Next are scrolled into view (a small window, a
  // long question): once per question, so the student may scroll back up.
  const std::string graded = asked && asked->grade ? asked->question.question.id : "";
  if (!graded.empty() && graded != scrolledTo_) ImGui::SetScrollHereY(1.0f);
  scrolledTo_ = graded;
}

void LessonPanel::drawQuestion(LessonController& lessons) {
  LessonController::Asked* asked = lessons.asked();
  if (!asked) return;
  LessonController::Asked& a = *asked;
  const quiz::Question& q = a.question.question;
  ImGui::PushTextWrapPos(0);
  ImGui::TextColored(kQuestion, a.review ? "Review question (%s)" : "Question (%s)", quiz::toString(q.kind));
  ImGui::TextUnformatted(printableUiText(q.prompt).c_str());
  const bool open = !a.grade;
  if (!open) ImGui::BeginDisabled();
  std::optional<quiz::Answer> answer;
  switch (q.kind) {
    case quiz::QuestionKind::Locate:
      ImGui::TextDisabled("Click it in the 3-D view.");
      if (open && lessons.answersGoToClass()) classPracticeNote("lesson_practice_ahead", practiceClickAheadNote());
      break;
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      for (int i = 0; i < int(a.choiceNames.size()); ++i) {
        ImGui::PushID(i);
        if (ImGui::RadioButton(printableUiText(a.choiceNames[std::size_t(i)]).c_str(), a.choice == i)) a.choice = i;
        ImGui::PopID();
      }
      if (a.choice < 0) ImGui::BeginDisabled();
      if (ImGui::Button("Answer")) (answer = quiz::Answer{})->choice = a.choice;
      if (a.choice < 0) ImGui::EndDisabled();
      break;
    case quiz::QuestionKind::Name:
      ImGui::InputTextWithHint("##name", "type the name", &a.text);
      if (a.text.empty()) ImGui::BeginDisabled();
      if (ImGui::Button("Answer")) (answer = quiz::Answer{})->text = a.text;
      if (a.text.empty()) ImGui::EndDisabled();
      break;
    case quiz::QuestionKind::Order: {
      ImGui::TextDisabled("Your path, first met first:");
      for (int i = 0; i < int(a.order.size()); ++i) {
        ImGui::PushID(i);
        if (ImGui::ArrowButton("up", ImGuiDir_Up) && i > 0) std::swap(a.order[std::size_t(i)], a.order[std::size_t(i - 1)]);
        ImGui::SameLine();
        if (ImGui::SmallButton("x")) {
          a.order.erase(a.order.begin() + i);
          ImGui::PopID();
          break;
        }
        ImGui::SameLine();
        ImGui::Text("%d. %s", i + 1, printableUiText(lessons.displayName(a.order[std::size_t(i)])).c_str());
        ImGui::PopID();
      }
      ImGui::TextDisabled("Offered (click to add):");
      for (std::size_t i = 0; i < a.question.choices.size(); ++i) {
        const std::string& id = a.question.choices[i];
        if (std::find(a.order.begin(), a.order.end(), id) != a.order.end()) continue;
        ImGui::PushID(int(i));
        if (ImGui::SmallButton(printableUiText(a.choiceNames[i]).c_str())) a.order.push_back(id);
        ImGui::PopID();
      }
      if (a.order.empty()) ImGui::BeginDisabled();
      if (ImGui::Button("Answer")) (answer = quiz::Answer{})->order = a.order;
      if (a.order.empty()) ImGui::EndDisabled();
      break;
    }
  }
  if (!open) ImGui::EndDisabled();
  if (answer)
    if (auto grade = lessons.answer(*answer); !grade) lessons.report("answer: " + grade.error().message);
  if (a.grade) {
    // The feedback says it first ("Correct: …", "Partly right: …", "Not quite: …"); its colour
    // agrees: green, amber for a partial score, red.
    const ImVec4 colour = a.grade->correct ? kRight : a.grade->score > 0 ? kPartly : kWrong;
    ImGui::TextColored(colour, "%s", printableUiText(a.grade->feedback).c_str());
    noteWidget("lesson_feedback");
    if (a.keptAsPractice) classPracticeNote("lesson_practice_kept", practicePickNote());
    if (a.review) ImGui::TextDisabled("Saved: the review queue is updated.");
    if (!a.grade->correct) {
      if (ImGui::Button("Show me"))  // the answer in its own view
        if (auto st = lessons.showMe(); !st) lessons.report(st.error().message);
      ImGui::SameLine();
      if (ImGui::Button("... on a slice"))  // and on a CT slice through it
        if (auto st = lessons.showMe(true); !st) lessons.report(st.error().message);
    }
  }
  if (a.review && ImGui::Button(a.grade ? "Done" : "Skip")) lessons.dismissReview();
  ImGui::PopTextWrapPos();
}

void LessonPanel::drawReview(LessonController& lessons) {
  ImGui::Separator();
  ImGui::Text("Due for review: %zu", lessons.due().size());
  ImGui::PushTextWrapPos(0);
  std::string list;
  for (const lessons::StructureProgress& p : lessons.due()) list += (list.empty() ? "" : ", ") + lessons.displayName(p.structureId);
  if (!list.empty()) ImGui::TextDisabled("%s", printableUiText(list).c_str());
  ImGui::PopTextWrapPos();
  if (ImGui::SmallButton("Review"))
    if (auto st = lessons.startReview(); !st) lessons.report("review: " + st.error().message);
}

}  // namespace at::app
