#include <algorithm>
#include <cmath>
#include <cstdio>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "core/strings.h"
#include "quiz/name_matching.h"
#include "ui/panels.h"
#include "core/printable_text.h"

namespace at::app {

namespace {
const ImVec4 kRight{0.5f, 1, 0.5f, 1}, kWrong{1, 0.5f, 0.4f, 1}, kPartly{1, 0.8f, 0.3f, 1}, kHeading{1, 0.75f, 0.3f, 1},
    kQuestion{0.6f, 0.8f, 1, 1};

std::string minutes(lessons::UnixSeconds seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%lld:%02lld", (long long)(seconds / 60), (long long)(seconds % 60));
  return text;
}

std::string percent(double fraction) { return std::to_string(int(std::lround(100 * fraction))) + "%"; }
}  // namespace

bool ExamPanel::active(const ExamController& exams) const {
  return exams.preparing() || exams.running() || exams.result();
}

void ExamPanel::drawList(ExamController& exams) {
  if (auto st = exams.sync(); !st) {
    ImGui::TextColored(kWrong, "exams: %s", st.error().message.c_str());
    return;
  }
  if (exams.rows().empty()) return;
  ImGui::Separator();
  ImGui::TextColored(kQuestion, "Practical exams");
  ImGui::PushTextWrapPos(0);
  for (const ExamController::ExamRow& row : exams.rows()) {
    ImGui::PushID(row.id.c_str());
    const bool locked = !row.missing.empty();
    const bool open = row.latest && !row.latest->finishedAt;
    if (locked) ImGui::BeginDisabled();
    if (ImGui::SmallButton(open ? "Resume" : row.latest ? "Again" : "Start"))
      if (auto st = exams.start(row.id); !st) exams.report(st.error().message);
    if (locked) ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::TextColored(locked ? ImVec4(0.6f, 0.6f, 0.6f, 1) : kHeading, "%s", printableUiText(row.title).c_str());
    std::string facts = "  " + str::countOf(row.count, "item") + ", " + std::to_string(row.timeLimitS / 60) + " min";
    if (row.passScore) facts += ", pass mark " + percent(*row.passScore);
    ImGui::TextDisabled("%s", printableUiText(facts).c_str());
    if (locked) {
      ImGui::TextDisabled("  locked: finish %s first", printableUiText(str::join(row.missing, ", ")).c_str());
    } else if (open) {
      ImGui::TextDisabled("  in progress: the clock runs on");
    } else if (row.latest) {
      const std::string verdict = !row.latest->passed ? "" : *row.latest->passed ? ", passed" : ", not passed";
      ImGui::TextColored(row.latest->passed.value_or(true) ? kRight : kWrong, "  last attempt %s%s",
                         percent(row.latest->score).c_str(), verdict.c_str());
    }
    ImGui::PopID();
  }
  ImGui::PopTextWrapPos();
}

void ExamPanel::draw(ExamController& exams) {
  if (auto title = exams.preparing()) {
    ImGui::TextColored(kHeading, "%s", title->c_str());
    ImGui::TextDisabled("Preparing the exam: drawing its items...");
    return;
  }
  if (exams.result()) {
    drawResults(exams);
    return;
  }
  drawItem(exams);
}

void ExamPanel::drawItem(ExamController& exams) {
  const lessons::ExamSpec* exam = exams.exam();
  const auto& item = exams.item();
  if (!exam || !item) return;
  ImGui::PushTextWrapPos(0);
  ImGui::TextColored(kHeading, "%s", printableUiText(exam->title).c_str());
  const lessons::UnixSeconds left = exams.secondsLeft();
  ImGui::TextColored(left < 60 ? kWrong : ImVec4(1, 1, 1, 1), "%s left", minutes(left).c_str());
  ImGui::SameLine();
  ImGui::TextDisabled("- %d of %d answered", exams.answeredCount(), exams.itemCount());
  // The items: answered ones are marked as saved, never as right or wrong.
  for (int i = 0; i < exams.itemCount(); ++i) {
    if (i % 6) ImGui::SameLine();
    ImGui::PushID(i);
    const bool here = i == exams.position();
    if (here) ImGui::PushStyleColor(ImGuiCol_Button, ImGui::GetStyleColorVec4(ImGuiCol_ButtonActive));
    const std::string label = std::to_string(i + 1) + (exams.itemAnswered(i) ? "*" : "");
    if (ImGui::SmallButton(label.c_str()) && !here)
      if (auto st = exams.goTo(i); !st) exams.report(st.error().message);
    if (here) ImGui::PopStyleColor();
    ImGui::PopID();
  }
  ImGui::TextDisabled("* answered (saved; marked only at the end)");
  ImGui::Separator();
  ImGui::TextColored(kQuestion, "Item %d", item->position + 1);
  ImGui::TextUnformatted(printableUiText(item->prompt).c_str());
  std::optional<quiz::Answer> answer;
  if (item->answered) {
    ImGui::TextDisabled("Answer saved.");
  } else {
    switch (item->kind) {
      case quiz::QuestionKind::Locate:
        ImGui::TextDisabled(item->locateView == lessons::ExamLocateView::Slice
                                ? "Click it on the CT slice."
                                : "Click it in the 3-D view (drag to turn the view).");
        break;
      case quiz::QuestionKind::Identify:
      case quiz::QuestionKind::Relation:
        for (int i = 0; i < int(item->choiceNames.size()); ++i) {
          ImGui::PushID(i);
          if (ImGui::RadioButton(printableUiText(item->choiceNames[std::size_t(i)]).c_str(), exams.choice == i)) exams.choice = i;
          ImGui::PopID();
        }
        if (exams.choice < 0) ImGui::BeginDisabled();
        if (ImGui::Button("Answer")) (answer = quiz::Answer{})->choice = exams.choice;
        if (exams.choice < 0) ImGui::EndDisabled();
        break;
      case quiz::QuestionKind::Name:
      case quiz::QuestionKind::Order:
        ImGui::InputTextWithHint("##name", "type the name", &exams.text);
        if (exams.text.empty()) ImGui::BeginDisabled();
        if (ImGui::Button("Answer")) (answer = quiz::Answer{})->text = exams.text;
        if (exams.text.empty()) ImGui::EndDisabled();
        break;
    }
  }
  if (answer)
    if (auto st = exams.answer(*answer); !st) exams.report("answer: " + st.error().message);
  ImGui::Separator();
  if (ImGui::Button("Hand in")) {
    if (auto st = exams.finish(); !st) exams.report(st.error().message);
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Finish now: unanswered items count as wrong");
  ImGui::SameLine();
  if (ImGui::Button("Leave")) exams.leave();
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Answers are saved; the clock runs on; Resume continues");
  ImGui::PopTextWrapPos();
}

void ExamPanel::drawResults(ExamController& exams) {
  const lessons::ExamResult& r = *exams.result();
  const lessons::ExamSpec* exam = exams.exam();
  ImGui::PushTextWrapPos(0);
  if (exam) ImGui::TextColored(kHeading, "%s", printableUiText(exam->title).c_str());
  ImGui::TextUnformatted(r.timeRanOut ? "Time is up." : "Handed in.");
  ImGui::Text("%d of %s right, score %s", r.correct, str::countOf(long(r.items.size()), "item").c_str(),
              percent(r.score).c_str());
  if (r.passed && exam)
    ImGui::TextColored(*r.passed ? kRight : kWrong, "%s (pass mark %s)", *r.passed ? "Passed" : "Not passed",
                       percent(exam->passScore.value_or(0)).c_str());
  if (ImGui::Button("Back to the lessons")) {
    exams.closeResults();
    ImGui::PopTextWrapPos();
    return;
  }
  ImGui::Separator();
  // The review: each item, the answer given and the right one; "show" puts the answer up in its
  // own view, "slice" on a slice through it as well.
  for (int i = 0; i < int(r.items.size()); ++i) {
    const lessons::ExamItemResult& x = r.items[std::size_t(i)];
    const ImVec4 colour = !x.answered ? ImVec4(0.6f, 0.6f, 0.6f, 1) : x.correct ? kRight : x.score > 0 ? kPartly : kWrong;
    const char* mark = !x.answered ? "not answered" : x.correct ? "right" : x.score > 0 ? "partly right" : "wrong";
    ImGui::PushID(i);
    ImGui::TextColored(colour, "%d. %s (%s)", x.position + 1, printableUiText(x.prompt).c_str(), mark);
    ImGui::TextDisabled("you: %s  -  answer: %s", printableUiText(x.answered ? x.yourAnswer : "(none)").c_str(),
                        printableUiText(x.rightAnswer).c_str());
    if (ImGui::SmallButton("show"))
      if (auto st = exams.showResultItem(i); !st) exams.report(st.error().message);
    ImGui::SameLine();
    if (ImGui::SmallButton("slice"))
      if (auto st = exams.showResultItem(i, true); !st) exams.report(st.error().message);
    ImGui::PopID();
  }
  ImGui::PopTextWrapPos();
}

void ExamPanel::drawSlice(DesktopModel& model, float x, float y, float w, float h) {
  const auto& slice = model.examSlice();
  const bool answer = slice && !slice->highlighted.empty();  // "show me on a slice"
  if (!slice || (!answer && !model.exams().running())) return;
  if (!slice_ || sliceRevision_ != slice->revision) {
    sliceRevision_ = slice->revision;
    render::RgbaImage rgba(slice->image.width, slice->image.height);
    for (int py = 0; py < rgba.height; ++py)
      for (int px = 0; px < rgba.width; ++px) {
        const std::uint8_t* p = slice->image.pixel(px, py);
        std::uint8_t* q = &rgba.rgba[(std::size_t(py) * std::size_t(rgba.width) + std::size_t(px)) * 4];
        q[0] = p[0], q[1] = p[1], q[2] = p[2], q[3] = 255;
      }
    if (!slice_) {
      auto texture = render::gl::ImageTexture::create();
      if (!texture) {
        sliceError_ = texture.error().message;
        return;
      }
      slice_ = std::move(*texture);
    }
    if (auto st = slice_->upload(rgba); !st) sliceError_ = st.error().message;
  }
  ImGui::SetNextWindowPos(ImVec2(x, y));
  ImGui::SetNextWindowSize(ImVec2(w, h));
  ImGui::Begin("Exam slice", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoTitleBar | ImGuiWindowFlags_NoScrollbar);
  if (answer) {
    const Structure* shown = model.dataset().findStructure(slice->highlighted);
    const std::string name = shown && !shown->displayName.empty() ? shown->displayName : slice->highlighted;
    ImGui::TextDisabled("Axial CT slice %d: the %s in colour, framed.", slice->request.index,
                        printableUiText(quiz::nameInSentence(name)).c_str());
    ImGui::SameLine();
    if (ImGui::SmallButton("Back to the 3-D view")) {
      model.closeAnswerSlice();
      ImGui::End();
      return;
    }
  } else {
    ImGui::TextDisabled("Axial CT slice %d (labels hidden): click the structure asked for.", slice->request.index);
  }
  if (!sliceError_.empty()) ImGui::TextColored(kWrong, "%s", sliceError_.c_str());
  const ImVec2 avail = ImGui::GetContentRegionAvail();
  const float scale = std::max(0.1f, std::min(avail.x / float(slice->image.width), avail.y / float(slice->image.height)));
  const ImVec2 size(float(slice->image.width) * scale, float(slice->image.height) * scale);
  ImGui::SetCursorPosX(ImGui::GetCursorPosX() + std::max(0.0f, (avail.x - size.x) * 0.5f));
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  if (slice_ && slice_->handle()) {
    ImGui::Image(reinterpret_cast<ImTextureID>(slice_->handle()), size);
    if (slice->request.layout) drawEdgeLetters(*slice->request.layout);
    if (ImGui::IsItemClicked(ImGuiMouseButton_Left)) {
      const ImVec2 m = ImGui::GetMousePos();
      model.clickSlice((m.x - origin.x) / scale, (m.y - origin.y) / scale);
    }
  }
  ImGui::End();
}

}  // namespace at::app
