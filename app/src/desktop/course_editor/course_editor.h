// The desktop's course editor without drawing (the Course editor window draws it; the UI script
// drives the same commands): an instructor's draft of a course on the dataset on screen — lessons
// with prerequisites; show steps captured from the view (structure, preset with its t, named
// view, the camera as the author left it and the clipping plane) with a title and text; questions of every kind; steps reordered, duplicated, deleted and
// previewed as a student will see them; live validation naming each problem by its field path (as
// the course reader does); saving into the database (the next version when it changes a stored
// course), exporting a package, and Open course… (importing one).
//
// A locate question is checked before it is added (question_visibility.h): seconds on a real CT,
// so the check runs on the editor's worker thread and the window keeps drawing meanwhile; poll(),
// each frame, adds the question (or refuses it) once the check ends.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "course_packages.h"
#include "learning_session.h"
#include "question_visibility.h"
#include "lessons/curriculum.h"
#include "render/preset.h"

namespace at::app {

class CourseEditor {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // What the view shows, for a show step or a question's scene.
  struct Capture {
    std::string structure;
    render::Preset preset;   // with the view's t
    lessons::CameraView view = lessons::CameraView::LateralRight;  // the last named view chosen
    std::optional<lessons::StepCamera> camera;  // where the camera is now (orbited, zoomed, panned)
    std::optional<lessons::StepClip> clip;      // the clipping plane, when one is on
  };
  // Shows a step as a student sees it: its scene (structure, preset id, named view, camera, clip),
  // with the preset `captured` when the draft holds it, else the preset id as a lesson finds it.
  using Preview = std::function<void(const lessons::QuestionScene& scene, const std::optional<render::Preset>& captured)>;

  // Whether a locate question can be answered in the view captured for it (question_visibility.h),
  // on the dataset on screen, in two parts. LocateViewCheck is called on the UI thread when Add is
  // pressed, never while work it returned still runs; it returns the work, which runs on the
  // editor's worker thread and so must read nothing the UI thread may change meanwhile (it takes
  // copies, or reads what stays unchanged until stopCheck returns). The work's `cancel` is set when
  // the check is stopped or its result no longer wanted; it should then return soon (its result is
  // dropped).
  using LocateCheckWork = std::function<Result<LocateCheck>(const std::atomic<bool>& cancel)>;
  using LocateViewCheck = std::function<LocateCheckWork(const quiz::Question& question, const lessons::QuestionScene& scene,
                                                        const render::Preset& preset)>;

  // `session` and `library` outlive the editor. `events` receives course_edited, course_saved,
  // course_exported, course_imported and, for a locate question's check, course_question_checking
  // and course_question_checked. `checkLocate` (may be empty: no check) is asked before a locate
  // question is added.
  CourseEditor(LearningSession& session, const render::PresetLibrary& library, EventSink events, Preview preview,
               LocateViewCheck checkLocate = {});
  // Cancels a running check and waits for its work to end, before anything it reads goes (no event).
  ~CourseEditor();
  CourseEditor(const CourseEditor&) = delete;
  CourseEditor& operator=(const CourseEditor&) = delete;

  bool windowOpen = false;
  bool editing() const { return draft_.has_value(); }
  const lessons::Course& draft() const { return *draft_; }
  std::size_t lessonIndex() const { return lesson_; }
  // Bumped on every change of the draft.
  std::uint64_t revision() const { return revision_; }

  // A new course `id` on `datasetId` with one empty lesson "<id>.lesson_1" [course_new].
  Status newCourse(const std::string& id, const std::string& title, const std::string& datasetId);
  // A stored course, to edit; saving stores it as the next version [course_open].
  Status openCourse(const std::string& courseId);
  Status setTitle(const std::string& title, const std::string& summary);

  // Lessons: added after the last (id "<course>.<identifier of the title>"), chosen for the step
  // commands, and their prerequisites (lesson ids of this course) [course_lesson].
  Status addLesson(const std::string& title);
  Status selectLesson(std::size_t index);
  Status setPrerequisites(const std::vector<std::string>& lessonIds);

  // Steps of the chosen lesson, appended. A show step's preset is the captured one, stored with
  // the course as "<lesson id>.show_<n>" [course_show, course_question].
  Status addShow(const Capture& capture, const std::string& title, const std::string& text);
  // `question.id` empty: "<lesson id>.q<n>". A locate question needs `scene` (a neighbour's view).
  // A locate question is refused (nothing changes) when its captured view cannot be answered in:
  // the click on its target's centre picks something else, or nothing is drawn where it picks.
  //
  // A locate question with a scene, when the editor has a check, is checked on the worker: the
  // call checks what it can at once (a lesson, a free id), takes a snapshot of the question, its
  // scene and the view's preset, starts the check (event course_question_checking {"question",
  // "target"}) and returns; checking() is true until poll() applies the result, on a later frame,
  // to that snapshot: the question is appended to the lesson that was chosen when it was asked
  // (course_edited), or refused with nothing changed (checkError() says why, with the text a
  // synchronous check gave). Event course_question_checked {"question", "added", "ms", "message"
  // when not added}. Meanwhile the draft stays editable, except that adding a step (show or
  // question) is refused (Conflict), so that steps stay in the order they were asked for; a new or
  // opened course drops the result (the check is cancelled; checkError() is a Cancelled error).
  Status addQuestion(quiz::Question question, const std::optional<Capture>& scene);
  // A locate question's check is running (addQuestion); adding a step waits for its end.
  bool checking() const { return job_ != nullptr; }
  // What the last addQuestion's check refused, or why its result was dropped; reset by the next
  // addQuestion.
  const std::optional<Error>& checkError() const { return checkError_; }
  // Each frame: applies a finished check's result (addQuestion).
  void poll();
  // Cancels a running check and waits for its work to end (before what it reads is replaced: the
  // dataset on screen; closing); its question is not added (checkError() is a Cancelled error).
  void stopCheck();
  Status moveStep(std::size_t from, std::size_t to);
  Status duplicateStep(std::size_t index);  // the copy follows it; a question's copy gets a new id
  Status deleteStep(std::size_t index);
  // Shows the step as a student sees it [course_preview]: its view, and while the preview lasts
  // its heading and text or prompt; names hidden for a question a name would give away.
  Status previewStep(std::size_t index);
  struct Previewing {
    std::size_t step = 0;           // in the chosen lesson
    lessons::StepKind kind = lessons::StepKind::Show;
    std::string structure;          // selected by the preview
    std::string heading, text;      // show: title and text; question: its kind and prompt
    bool namesHidden = false;       // a student sees no structure name (namesGiveAway)
  };
  // The preview on screen; it ends with any change of the draft or another lesson chosen.
  const std::optional<Previewing>& previewing() const { return previewing_; }
  void endPreview() { previewing_.reset(); }

  // Live validation: each problem as "<field path>: <what is wrong>"; empty when it can be saved.
  const std::vector<std::string>& problems() const { return problems_; }
  // Stores the draft (and its captured presets); a stored course with other content is replaced
  // by the next version [course_saved].
  Result<db::SeedOutcome> save();
  // Saves, then writes the course as a package [course_exported].
  Result<CourseExportReport> exportPackage(const std::string& path, bool referenceVolume, const std::string& note);
  // Open course…: imports a package [course_imported]; its course can then be opened to edit.
  Result<CourseImportReport> openPackage(const std::string& path, const std::string& volumePath);

  // The draft as an event (steps in order: kind, structure or target, title or prompt).
  nlohmann::json stateEvent() const;

 private:
  Result<lessons::Lesson*> lesson();
  void changed();
  // Stores the capture's preset in captured_, named after `lesson`'s next step; gives its id.
  std::string capturePreset(const lessons::Lesson& lesson, const Capture& capture);
  Status requireNoCheck() const;  // a Conflict while a locate question is being checked
  // A step of the lesson `lessonId` of this draft with its captured scene, appended; the question
  // id, when `freshId`, made anew if it was taken meanwhile.
  Status appendQuestion(const std::string& lessonId, lessons::Step step, const std::optional<Capture>& scene, bool freshId);
  // A new draft replaces the one a running check's question belongs to.
  void dropCheck(const std::string& why);

  LearningSession& session_;
  const render::PresetLibrary& library_;
  EventSink events_;
  Preview preview_;
  LocateViewCheck checkLocate_;
  std::optional<lessons::Course> draft_;
  std::optional<int> storedVersion_;                  // of the course opened, or saved
  std::map<std::string, render::Preset> captured_;    // presets of this draft by id
  std::size_t lesson_ = 0;
  std::vector<std::string> problems_;
  std::optional<Previewing> previewing_;
  std::uint64_t revision_ = 0;
  struct CheckJob;
  std::unique_ptr<CheckJob> job_;  // the locate check running on its worker, until poll() takes it
  std::optional<Error> checkError_;
};

}  // namespace at::app
