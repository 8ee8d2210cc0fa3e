// The desktop's practical exams without drawing (the Lessons panel draws them; the UI script drives
// the same commands): the exams of the lesson panel's course with their prerequisites and the
// student's latest attempt, and one attempt through lessons::ExamSession — items drawn when it
// starts (answer keys computed on a thread), labels hidden throughout, answers saved as they are
// given with no grade shown, items visited in any order, a clock that hands in by itself when the
// time is up, and every item's result and the score only at the end.
//
// The view follows the item through `ShowItem`: identify and name items highlight their target;
// a locate item shows its region (a neighbour selected) in the 3-D view — the model turns the view
// to a side from which the target can be clicked — or an axial CT slice through the target, on
// which the student clicks. A click reaches clicked() through the model either way.
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "db/exam_store.h"
#include "learning_session.h"
#include "lesson_controller.h"
#include "lessons/exam.h"

namespace at::app {

class ExamController {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // What the view shows for an item; nullopt: the exam's view ends (no slice, no turning).
  struct ItemScene {
    lessons::QuestionScene scene;
    std::string target;     // the item's structure (for framing and picking; never shown)
    bool locate = false;    // a click answers it
    bool slice = false;     // locate on an axial slice through the target, not in the 3-D view
    // The review after the exam: the target highlighted on the axial slice through its anchor
    // (shown in place of the 3-D view), besides the scene.
    bool answerOnSlice = false;
  };
  using ShowItem = std::function<void(const std::optional<ItemScene>&)>;
  using RenderStateSource = std::function<lessons::RenderState()>;

  // `session` and `lessons` (whose user and course the exams follow) outlive the controller.
  ExamController(LearningSession& session, LessonController& lessons, EventSink events, ShowItem show,
                 RenderStateSource renderState);
  ~ExamController();

  // --- State, for the panel -------------------------------------------------------------------
  struct ExamRow {
    std::string id, title, instructions;
    int count = 0, timeLimitS = 0;
    std::optional<double> passScore;
    std::vector<std::string> missing;              // unfinished prerequisite lessons (titles)
    std::optional<lessons::ExamAttempt> latest;    // the user's latest attempt
  };
  // The exams of the lesson panel's course (refreshed by refresh()).
  const std::vector<ExamRow>& rows() const { return rows_; }
  std::optional<std::string> preparing() const;    // the exam's title while its items are drawn
  bool running() const { return session_ && !result_ && !pending_; }
  const lessons::ExamSpec* exam() const { return running() || result_ ? &session_->exam() : nullptr; }
  int itemCount() const { return session_ ? session_->itemCount() : 0; }
  int answeredCount() const;
  lessons::UnixSeconds secondsLeft() const { return running() ? session_->secondsLeft() : 0; }
  // The item on screen and what the student has composed for it (choice, typed name).
  int position() const { return position_; }
  const std::optional<lessons::ExamItemView>& item() const { return item_; }
  int choice = -1;
  std::string text;
  // Item `i` was answered (its answer is saved; nothing says whether it was right).
  bool itemAnswered(int i) const;
  const std::optional<lessons::ExamResult>& result() const { return result_; }
  std::string displayName(const std::string& structureId) const;
  // Structure names must not be shown anywhere (the whole attempt, preparing included).
  bool namesHidden() const { return running() || pending_.has_value(); }
  // The item on screen is an unanswered locate item in the 3-D view / on the slice.
  bool wantsClick() const;
  bool wantsSliceClick() const;
  std::optional<std::string> itemTarget() const;
  bool acceptsClickDistance() const;  // a miss within the item's tolerance may still count

  // --- Commands (the panel's widgets and the UI script) ---------------------------------------
  Status refresh();
  // refresh() when the lesson panel's user, course or finished lessons changed (each frame).
  Status sync();
  // Starts (or resumes) the exam; its items are drawn on a thread, poll() completes the start
  // [exam_started, exam_item; exam_refused]. Refused while a lesson runs or is being prepared.
  Status start(const std::string& examId);
  // Each frame: completes a start; hands in when the time is up [exam_finished].
  void poll();
  std::optional<Status> takeStartResult();
  Status goTo(int position);                        // [exam_item]
  // Saves the answer to the item on screen (no grade shown) and moves to the next unanswered
  // item [exam_answered, exam_item].
  Status answer(const quiz::Answer& answer);
  // A click on `structure` ("" for none), in the 3-D view or on the slice, with its weighted
  // distance from the target (negative: unknown). True when it answered the item.
  bool clicked(const std::string& structure, double distanceMm = -1);
  Status finish();                                   // hands in [exam_finished]
  void leave();                                      // answers saved, the clock runs on
  void closeResults();
  // The review after the exam: result item `index` (0-based, as result()->items) in its show-me
  // scene (the target in its own WDT view, lessons::ExamItemResult::scene), `onSlice` also on a
  // slice through the target [exam_review_item]. Only once the exam is handed in.
  Status showResultItem(int index, bool onSlice = false);
  // Shows an error in the lesson panel (and on stderr).
  void report(const std::string& text) { lessons_.report(text); }

 private:
  Status completeStart();
  Status show(int position);
  void finished(const lessons::ExamResult& result);

  LearningSession& learning_;
  LessonController& lessons_;
  EventSink events_;
  ShowItem show_;
  RenderStateSource renderState_;
  db::SqlExamRepository repository_;
  std::vector<ExamRow> rows_;
  std::string rowsKey_;  // user, course and finished lessons the rows were made for
  std::vector<Structure> structures_;  // of the exam's dataset (names for the results)
  std::unique_ptr<lessons::ExamSession> session_;
  struct Pending {
    std::future<Status> started;
    std::string examId, title;
  };
  std::optional<Pending> pending_;  // declared after session_: joined before it is destroyed
  std::optional<Status> startResult_;
  int position_ = 0;
  std::optional<lessons::ExamItemView> item_;
  std::chrono::steady_clock::time_point shownAt_;
  std::optional<lessons::ExamResult> result_;
};

}  // namespace at::app
