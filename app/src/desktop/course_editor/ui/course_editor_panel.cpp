// The Course editor window: draws CourseEditor's state and calls its commands (the UI script's
// course_* actions call the same ones).
#include <imgui.h>
#include <imgui_stdlib.h>

#include "core/strings.h"
#include "ui/list_rows.h"
#include "ui/panels.h"
#include "core/printable_text.h"

namespace at::app {

namespace {

const ImVec4 kProblem(1, 0.5f, 0.4f, 1), kGood(0.6f, 1, 0.6f, 1);
constexpr const char* kKinds[] = {"name", "identify", "locate", "relation", "order"};

// The structure ids of the dataset on screen, and a combo over them.
std::vector<std::string> structureIds(const Dataset& dataset) {
  std::vector<std::string> ids;
  for (const Structure& s : dataset.structures) ids.push_back(s.id);
  return ids;
}

bool structureCombo(const char* label, const std::vector<std::string>& ids, int* index) {
  if (ids.empty()) return false;
  *index = std::clamp(*index, 0, int(ids.size()) - 1);
  bool changed = false;
  if (ImGui::BeginCombo(label, printableUiText(ids[std::size_t(*index)]).c_str())) {
    for (int i = 0; i < int(ids.size()); ++i)
      if (listRowSelectable(i, ids[std::size_t(i)], i == *index)) changed = (*index = i, true);
    ImGui::EndCombo();
  }
  return changed;
}

std::vector<std::string> commaList(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    if (std::string item = str::trim(text.substr(start, end - start)); !item.empty()) out.push_back(item);
    start = end + 1;
  }
  return out;
}

}  // namespace

void CourseEditorPanel::report(const Status& st, const std::string& done) {
  failed_ = !st;
  status_ = st ? done : st.error().message;
}

void CourseEditorPanel::draw(DesktopModel& model, float x, float y) {
  CourseEditor& editor = model.courseEditor();
  if (!editor.windowOpen) return;
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  ImGui::SetNextWindowSize(ImVec2(ImGui::GetFontSize() * 34, ImGui::GetFontSize() * 40), ImGuiCond_Appearing);
  if (!ImGui::Begin("Course editor", &editor.windowOpen)) {
    ImGui::End();
    return;
  }
  // A locate question's check ended since the last frame: added, or why not.
  if (checking_ && !editor.checking())
    report(editor.checkError() ? Status(tl::unexpected(*editor.checkError())) : Status{}, "question added");
  checking_ = editor.checking();
  if (editor.editing()) drawCourse(model);
  else drawStart(model);
  if (!status_.empty()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(failed_ ? kProblem : kGood, "%s", status_.c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::End();
}

void CourseEditorPanel::drawStart(DesktopModel& model) {
  CourseEditor& editor = model.courseEditor();
  ImGui::Text("New course on '%s'", printableUiText(model.courseDatasetId()).c_str());
  ImGui::InputText("id", &newId_);
  ImGui::InputText("title", &newTitle_);
  if (ImGui::Button("Create")) report(editor.newCourse(newId_, newTitle_, model.courseDatasetId()), "");
  ImGui::Separator();
  const auto& courses = model.lessons().courses();
  if (!courses.empty()) {
    courseChoice_ = std::clamp(courseChoice_, 0, int(courses.size()) - 1);
    if (ImGui::BeginCombo("stored course", printableUiText(courses[std::size_t(courseChoice_)].id).c_str())) {
      for (int i = 0; i < int(courses.size()); ++i)
        if (listRowSelectable(i, courses[std::size_t(i)].id, i == courseChoice_)) courseChoice_ = i;
      ImGui::EndCombo();
    }
    if (ImGui::Button("Edit")) report(editor.openCourse(courses[std::size_t(courseChoice_)].id), "");
    ImGui::Separator();
  }
  ImGui::TextUnformatted("Open course... (a .atcourse package)");
  ImGui::InputTextWithHint("package", "path to F.atcourse", &openPath_);
  ImGui::InputTextWithHint("volume", "only for a package that references its scan", &openVolume_);
  if (ImGui::Button("Open course")) {
    auto r = editor.openPackage(openPath_, openVolume_);
    report(r ? Status{} : Status(tl::unexpected(r.error())),
           r ? "course '" + r->courseId + "' version " + std::to_string(r->version) + ": " + db::toString(r->outcome) +
                   "; dataset '" + r->datasetId + "' " + toString(r->dataset)
             : "");
    if (r) (void)model.lessons().refresh();
  }
}

void CourseEditorPanel::drawCourse(DesktopModel& model) {
  CourseEditor& editor = model.courseEditor();
  const lessons::Course& course = editor.draft();
  ImGui::Text("%s (version %d) on '%s'", printableUiText(course.id).c_str(), course.version, printableUiText(course.datasetId).c_str());
  std::string title = course.title, summary = course.summary;
  if (ImGui::InputText("title", &title) | ImGui::InputText("summary", &summary)) report(editor.setTitle(title, summary), "");
  const std::size_t li = editor.lessonIndex();
  if (!course.lessons.empty() && ImGui::BeginCombo("lesson", printableUiText(course.lessons[li].title).c_str())) {
    for (std::size_t i = 0; i < course.lessons.size(); ++i)
      if (listRowSelectable(int(i), course.lessons[i].title, i == li)) report(editor.selectLesson(i), "");
    ImGui::EndCombo();
  }
  ImGui::InputTextWithHint("##lesson_title", "new lesson's title", &lessonTitle_);
  ImGui::SameLine();
  if (ImGui::Button("Add lesson")) report(editor.addLesson(lessonTitle_), "");
  if (li < course.lessons.size() && li > 0) {
    ImGui::TextUnformatted("requires:");
    std::vector<std::string> prerequisites = course.lessons[li].prerequisites;
    for (std::size_t i = 0; i < li; ++i) {
      const std::string& id = course.lessons[i].id;
      bool on = std::find(prerequisites.begin(), prerequisites.end(), id) != prerequisites.end();
      ImGui::SameLine();
      if (listRowCheckbox(int(i), course.lessons[i].title, &on)) {
        if (on) prerequisites.push_back(id);
        else prerequisites.erase(std::remove(prerequisites.begin(), prerequisites.end(), id), prerequisites.end());
        report(editor.setPrerequisites(prerequisites), "");
      }
    }
  }
  ImGui::Separator();
  drawSteps(model);
  ImGui::Separator();
  drawAddStep(model);
  ImGui::Separator();
  for (const std::string& problem : editor.problems()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(kProblem, "%s", printableUiText(problem).c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::BeginDisabled(!editor.problems().empty());
  if (ImGui::Button("Save")) {
    auto saved = editor.save();
    report(saved ? Status{} : Status(tl::unexpected(saved.error())),
           saved ? "saved as version " + std::to_string(editor.draft().version) : "");
    if (saved) (void)model.lessons().refresh();
  }
  ImGui::InputText("package file", &exportPath_);
  ImGui::Checkbox("leave the volume out (reference by checksum)", &reference_);
  if (reference_) ImGui::InputTextWithHint("note", "where to get the scan, its licence", &note_);
  if (ImGui::Button("Save and export")) {
    auto r = editor.exportPackage(exportPath_, reference_, note_);
    report(r ? Status{} : Status(tl::unexpected(r.error())), r ? exportPath_ + ": " + std::to_string(r->bytes) + " bytes" : "");
  }
  ImGui::EndDisabled();
  ImGui::SameLine();
  if (ImGui::Button("Close")) editor.windowOpen = false;
}

void CourseEditorPanel::drawSteps(DesktopModel& model) {
  CourseEditor& editor = model.courseEditor();
  const lessons::Course& course = editor.draft();
  if (editor.lessonIndex() >= course.lessons.size()) return;
  // A running lesson's or exam's question would be answered by the step list (its targets).
  if (model.lessons().namesHidden() || model.exams().namesHidden()) {
    ImGui::TextDisabled("The steps are hidden while a lesson or exam question is asked.");
    return;
  }
  const auto& steps = course.lessons[editor.lessonIndex()].steps;
  if (steps.empty()) ImGui::TextDisabled("No step yet: add one below.");
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const lessons::Step& s = steps[i];
    ImGui::PushID(int(i));
    std::string text = std::to_string(i + 1) + ". ";
    if (s.kind == lessons::StepKind::Show) text += "show " + s.show.structure + ": " + s.show.title;
    else if (s.kind == lessons::StepKind::Question) text += std::string(quiz::toString(s.question.kind)) + " " + s.question.target + ": " + s.question.prompt;
    else text += "study " + s.study.structure;
    if (ImGui::SmallButton("view")) report(editor.previewStep(i), "");
    ImGui::SameLine();
    if (ImGui::SmallButton("^") && i > 0) report(editor.moveStep(i, i - 1), "");
    ImGui::SameLine();
    if (ImGui::SmallButton("v") && i + 1 < steps.size()) report(editor.moveStep(i, i + 1), "");
    ImGui::SameLine();
    if (ImGui::SmallButton("copy")) report(editor.duplicateStep(i), "");
    ImGui::SameLine();
    if (ImGui::SmallButton("x")) report(editor.deleteStep(i), "");
    ImGui::SameLine();
    ImGui::TextUnformatted(printableUiText(text).c_str());
    ImGui::PopID();
  }
  drawPreview(model);
}

// What a student reads with the previewed step (the view shows its scene).
void CourseEditorPanel::drawPreview(DesktopModel& model) {
  const auto& preview = model.courseEditor().previewing();
  if (!preview) return;
  ImGui::Separator();
  ImGui::Text("Preview of step %zu, as a student sees it:", preview->step + 1);
  ImGui::TextColored(ImVec4(1, 0.75f, 0.3f, 1), "%s", printableUiText(preview->heading).c_str());
  ImGui::PushTextWrapPos(0);
  ImGui::TextUnformatted(printableUiText(preview->text).c_str());
  ImGui::PopTextWrapPos();
  if (model.previewHidesNames()) ImGui::TextDisabled("Structure names are hidden, as in the lesson.");
  else if (preview->namesHidden) ImGui::TextDisabled("Preview ended: another structure is selected.");
  if (ImGui::SmallButton("End preview")) model.courseEditor().endPreview();
}

void CourseEditorPanel::drawAddStep(DesktopModel& model) {
  CourseEditor& editor = model.courseEditor();
  ImGui::TextUnformatted("Show step: what the view shows now (structure, preset, t, view)");
  ImGui::InputText("heading", &showTitle_);
  ImGui::InputTextMultiline("text", &showText_, ImVec2(-1, ImGui::GetTextLineHeight() * 3));
  // While a locate question's view is checked (on a worker) no step is added: the steps keep the
  // order they were asked for.
  const bool checking = editor.checking();
  ImGui::BeginDisabled(checking);
  const bool addShow = ImGui::Button("Add show step");
  ImGui::EndDisabled();
  if (addShow) {
    auto capture = model.captureView();
    report(capture ? editor.addShow(*capture, showTitle_, showText_) : Status(tl::unexpected(capture.error())), "");
  }
  ImGui::Separator();
  ImGui::TextUnformatted("Question");
  ImGui::Combo("kind", &kind_, kKinds, IM_ARRAYSIZE(kKinds));
  const std::vector<std::string> ids = structureIds(model.dataset());
  structureCombo(kind_ == 3 ? "from" : kind_ == 4 ? "drill to" : "target", ids, &target_);
  ImGui::InputText("prompt", &prompt_);
  if (kind_ == 0) ImGui::InputTextWithHint("synonyms", "other accepted names, comma separated", &synonyms_);
  if (kind_ == 1) ImGui::TextDisabled("choices: the target and its 3 nearest structures (computed)");
  if (kind_ == 2) ImGui::SliderFloat("tolerance (mm)", &toleranceMm_, 0, 5, "%.1f");
  if (kind_ == 3) ImGui::InputTextWithHint("candidates", "structure ids, comma separated", &candidates_);
  if (kind_ == 4) structureCombo("entry", ids, &other_);
  ImGui::Checkbox("ask on what the view shows now", &onView_);
  if (kind_ == 2) ImGui::TextDisabled("a locate question needs the view of a neighbour of its target");
  ImGui::BeginDisabled(checking);
  const bool addQuestion = ImGui::Button("Add question");
  ImGui::EndDisabled();
  if (checking) {
    ImGui::SameLine();
    ImGui::TextDisabled("checking the view: can its target be seen and clicked?...");
  }
  if (addQuestion && !ids.empty()) {
    quiz::Question q;
    q.kind = quiz::parseQuestionKind(kKinds[kind_]).value_or(quiz::QuestionKind::Name);
    q.target = ids[std::size_t(target_)];
    q.prompt = prompt_;
    q.synonyms = commaList(synonyms_);
    q.toleranceMm = toleranceMm_;
    if (q.kind == quiz::QuestionKind::Relation) q.relation = {q.target, quiz::RelationKind::Nearest, commaList(candidates_), 0};
    if (q.kind == quiz::QuestionKind::Order) q.order = {std::nullopt, std::nullopt, ids[std::size_t(other_)], q.target, 2};
    std::optional<CourseEditor::Capture> scene;
    Status st;
    if (onView_ || q.kind == quiz::QuestionKind::Locate) {
      auto capture = model.captureView();
      if (capture) scene = *capture;
      else st = tl::unexpected(capture.error());
    }
    report(st ? editor.addQuestion(q, scene) : st, "");
    checking_ = editor.checking();
  }
}

}  // namespace at::app
