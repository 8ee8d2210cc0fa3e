// Practical exams: items drawn from the instructor's structures × kinds, answered with no feedback
// and no names, a clock that refuses late answers, results and a score at the end.
#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <set>

#include "in_memory_repositories.h"
#include "lessons/course_json.h"
#include "lessons/exam.h"

using namespace at;
using namespace at::lessons;

namespace {

const std::vector<std::string> kIds = {"cochlea", "vestibule", "stapes", "incus", "malleus"};

struct Fixture {
  test::InMemoryCurriculum curriculum;
  test::InMemoryProgress progress;
  test::InMemoryExams exams{progress};
  test::TableKeyComputer keys;
  UnixSeconds clock = 5'000'000;

  Fixture(int count = 6, std::vector<quiz::QuestionKind> kinds = {quiz::QuestionKind::Locate, quiz::QuestionKind::Identify,
                                                                   quiz::QuestionKind::Name}) {
    Course c;
    c.id = "toy";
    c.title = "Toy";
    c.datasetId = "phantom";
    Lesson one;
    one.id = "one";
    one.courseId = "toy";
    one.title = "Lesson one";
    Step show;
    show.show = {.structure = "cochlea",
                 .presetId = "cochlea_wdt",
                 .view = CameraView::LateralRight,
                 .title = "Cochlea",
                 .text = "Text.",
                 .camera = std::nullopt,
                 .clip = std::nullopt};
    one.steps = {show};
    c.lessons = {one};
    ExamSpec e;
    e.id = "toy.exam";
    e.title = "Toy exam";
    e.structures = {"cochlea", "vestibule", "stapes", "incus"};
    e.kinds = std::move(kinds);
    e.count = count;
    e.timeLimitS = 600;
    e.locateViews = {ExamLocateView::ThreeD, ExamLocateView::Slice};
    e.passScore = 0.5;
    c.exams = {e};
    curriculum.courseList = {c};
    std::vector<Structure> structures;
    for (std::size_t i = 0; i < kIds.size(); ++i) {
      Structure s;
      s.label = std::uint16_t(i + 1);
      s.id = kIds[i];
      s.displayName = std::string(1, char(std::toupper(kIds[i][0]))) + kIds[i].substr(1);
      structures.push_back(s);
    }
    curriculum.datasets["phantom"] = structures;
    keys.structureIds = kIds;
    // Distances along a line: cochlea 0, vestibule 1, stapes 2, incus 3, malleus 4 (mm).
    for (std::size_t i = 0; i < kIds.size(); ++i)
      for (std::size_t k = 0; k < kIds.size(); ++k)
        keys.distances[kIds[i]][kIds[k]] = std::abs(double(i) - double(k));
  }

  EngineOptions options() {
    EngineOptions o;
    o.clock = [this] { return clock; };
    return o;
  }
};

// The right answer to an item (a pick on the target, the key choice, the target's name).
quiz::Answer rightAnswer(const quiz::ResolvedQuestion& q) {
  quiz::Answer a;
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate: a.pick = quiz::Pick{.structure = q.question.target, .distanceMm = 0, .pixel = std::nullopt, .view = ""}; break;
    case quiz::QuestionKind::Identify: a.choice = q.keyChoice; break;
    default: a.text = q.question.target; break;
  }
  return a;
}

quiz::Answer wrongAnswer(const quiz::ResolvedQuestion& q) {
  quiz::Answer a;
  const std::string other = q.question.target == "malleus" ? "incus" : "malleus";
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate: a.pick = quiz::Pick{.structure = other, .distanceMm = 3.0, .pixel = std::nullopt, .view = ""}; break;
    case quiz::QuestionKind::Identify: a.choice = (q.keyChoice + 1) % int(q.choices.size()); break;
    default: a.text = other; break;
  }
  return a;
}

}  // namespace

TEST_CASE("ExamItems_EveryStructureOnceBeforeRepeats_FixedBySeed_LocateShowsANeighbour") {
  Fixture f;
  const ExamSpec& exam = f.curriculum.courseList[0].exams[0];
  auto items = drawExamItems(exam, f.curriculum.datasets["phantom"], f.keys, "seed-a");
  REQUIRE_MESSAGE(items, (items ? "" : items.error().message));
  REQUIRE(items->size() == 6);
  std::set<std::string> firstFour;
  for (int i = 0; i < 4; ++i) firstFour.insert((*items)[std::size_t(i)].question.question.target);
  CHECK(firstFour.size() == 4);  // four structures before any repeats
  std::set<std::pair<std::string, int>> pairs;
  int locate = 0;
  for (const ExamItem& item : *items) {
    const quiz::Question& q = item.question.question;
    CHECK(pairs.insert({q.target, int(q.kind)}).second);  // no structure × kind twice
    CHECK(q.id == "toy.exam." + std::string(quiz::toString(q.kind)) + "." + q.target);
    if (q.kind == quiz::QuestionKind::Locate) {
      CHECK(item.scene.structure != q.target);  // the region, not the marked target
      CHECK(f.keys.distances[q.target][item.scene.structure] == 1.0);  // its nearest neighbour
      CHECK((item.locateView == (locate % 2 == 0 ? ExamLocateView::ThreeD : ExamLocateView::Slice)));
      CHECK(q.prompt.find("Locate the ") == 0);
      ++locate;
    } else {
      CHECK(item.scene.structure == q.target);  // marked
      CHECK(q.prompt.find(q.target) == std::string::npos);
      if (q.kind == quiz::QuestionKind::Identify) {
        CHECK(item.question.choices.size() == 4);
        CHECK(item.question.choices[std::size_t(item.question.keyChoice)] == q.target);
      }
    }
  }
  // The same seed draws the same items; another seed another order.
  auto again = drawExamItems(exam, f.curriculum.datasets["phantom"], f.keys, "seed-a");
  for (std::size_t i = 0; i < items->size(); ++i)
    CHECK((*again)[i].question.question.id == (*items)[i].question.question.id);
  bool differs = false;
  for (const char* seed : {"seed-b", "seed-c", "seed-d"}) {
    auto other = drawExamItems(exam, f.curriculum.datasets["phantom"], f.keys, seed);
    for (std::size_t i = 0; i < items->size(); ++i)
      differs = differs || (*other)[i].question.question.id != (*items)[i].question.question.id;
  }
  CHECK(differs);
  // A structure the dataset lacks is named.
  ExamSpec bad = exam;
  bad.structures.push_back("nope");
  auto refused = drawExamItems(bad, f.curriculum.datasets["phantom"], f.keys, "x");
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("'nope'") != std::string::npos);
}

TEST_CASE("ExamSession_HidesNamesAndFeedback_RecordsEveryAnswer_ScoresAtTheEnd") {
  Fixture f;
  ExamSession session(f.curriculum, f.progress, f.exams, f.keys, f.options());
  REQUIRE(session.start(1, "toy.exam"));
  CHECK_FALSE(session.resumed());
  REQUIRE(session.itemCount() == 6);
  CHECK(session.secondsLeft() == 600);
  // Right, wrong, right, wrong, right; the last one left unanswered.
  std::vector<bool> right;
  for (int i = 0; i < 5; ++i) {
    auto view = session.item(i);
    REQUIRE(view);
    // Names never show: only a locate prompt names what to find; choices are names to pick from.
    if (view->kind != quiz::QuestionKind::Locate)
      for (const std::string& id : kIds) CHECK(view->prompt.find(id) == std::string::npos);
    auto q = session.itemQuestion(i);
    REQUIRE(q);
    const bool ok = i % 2 == 0;
    right.push_back(ok);
    f.clock += 30;
    auto answered = session.answer(i, ok ? rightAnswer(*q) : wrongAnswer(*q), 2500);
    REQUIRE_MESSAGE(answered, (answered ? "" : answered.error().message));  // a Status: no grade to show
    CHECK(session.item(i)->answered);
  }
  CHECK(session.nextUnanswered() == std::optional<int>(5));
  CHECK_FALSE(session.answer(0, rightAnswer(*session.itemQuestion(0)), 1));  // once only
  // Every answer was recorded as it was given: memory states and the review log (source exam).
  CHECK(f.progress.log.size() == 5);
  for (const auto& e : f.progress.log) CHECK((e.source == AnswerSource::Exam));
  CHECK((f.progress.log[1].rating == Rating::Again));

  auto result = session.finish();
  REQUIRE(result);
  CHECK(result->score == doctest::Approx(3.0 / 6.0));
  CHECK(result->answered == 5);
  CHECK(result->correct == 3);
  CHECK(result->passed == std::optional<bool>(true));
  CHECK_FALSE(result->timeRanOut);
  REQUIRE(result->items.size() == 6);
  for (int i = 0; i < 5; ++i) CHECK(result->items[std::size_t(i)].correct == right[std::size_t(i)]);
  CHECK_FALSE(result->items[5].answered);
  CHECK(result->items[5].feedback.find("Not answered") == 0);
  CHECK_FALSE(result->items[1].feedback.empty());
  // Stored: the attempt is finished with its score; a new start draws a new attempt.
  REQUIRE(f.exams.attemptList.size() == 1);
  CHECK(f.exams.attemptList[0].finishedAt.has_value());
  CHECK(f.exams.attemptList[0].score == doctest::Approx(0.5));
  CHECK(f.exams.attemptList[0].passed == std::optional<bool>(true));
  ExamSession next(f.curriculum, f.progress, f.exams, f.keys, f.options());
  REQUIRE(next.start(1, "toy.exam"));
  CHECK(f.exams.attemptList.size() == 2);
}

TEST_CASE("ExamSession_TheClockRefusesLateAnswersAndAResumeAfterTheDeadlineFinishes") {
  Fixture f;
  {
    ExamSession session(f.curriculum, f.progress, f.exams, f.keys, f.options());
    REQUIRE(session.start(1, "toy.exam"));
    REQUIRE(session.answer(0, rightAnswer(*session.itemQuestion(0)), 100));
    // The process ends here; the student comes back within the time: the same items, item 1 kept.
  }
  f.clock += 100;
  ExamSession resumed(f.curriculum, f.progress, f.exams, f.keys, f.options());
  REQUIRE(resumed.start(1, "toy.exam"));
  CHECK(resumed.resumed());
  CHECK(resumed.secondsLeft() == 500);
  CHECK(resumed.nextUnanswered() == std::optional<int>(1));
  CHECK(resumed.item(0)->answered);

  // Past the deadline: refused, nothing recorded.
  f.clock += 500;
  CHECK(resumed.secondsLeft() == 0);
  auto late = resumed.answer(1, rightAnswer(*resumed.itemQuestion(1)), 100);
  REQUIRE_FALSE(late);
  CHECK(late.error().message.find("time is up") != std::string::npos);
  CHECK(f.progress.log.size() == 1);
  auto result = resumed.finish();
  REQUIRE(result);
  CHECK(result->timeRanOut);
  CHECK(result->answered == 1);
  CHECK(result->score == doctest::Approx(1.0 / 6.0));
  CHECK(result->passed == std::optional<bool>(false));
  CHECK(*f.exams.attemptList[0].finishedAt == f.exams.attemptList[0].deadline);
}

TEST_CASE("ExamSession_PrerequisitesStorageFailuresAndBadAnswers") {
  Fixture f;
  f.curriculum.courseList[0].exams[0].prerequisites = {"one"};
  ExamSession session(f.curriculum, f.progress, f.exams, f.keys, f.options());
  auto blocked = session.start(1, "toy.exam");
  REQUIRE_FALSE(blocked);
  CHECK(blocked.error().message == "exam 'toy.exam' (Toy exam) needs 'one' (Lesson one) finished first");
  CHECK(f.exams.attemptList.empty());
  CHECK_FALSE(session.start(1, "nope"));

  f.curriculum.courseList[0].exams[0].prerequisites.clear();
  REQUIRE(session.start(1, "toy.exam"));
  f.exams.failNextRecord = true;
  auto failed = session.answer(0, rightAnswer(*session.itemQuestion(0)), 10);
  REQUIRE_FALSE(failed);
  CHECK(failed.error().message.find("disk full") != std::string::npos);
  CHECK_FALSE(session.item(0)->answered);
  CHECK(session.answer(0, rightAnswer(*session.itemQuestion(0)), 10));  // can be given again
  quiz::Answer empty;
  CHECK_FALSE(session.answer(1, empty, 10));  // does not fit: reported, nothing recorded
  CHECK(f.progress.log.size() == 1);
}

TEST_CASE("ExamJson_ReadsTheExamAndNamesTheFieldOfEveryMistake") {
  const std::string head =
      R"({"schema": 1, "id": "c", "title": "C", "dataset": "phantom", "lessons": [{"id": "l", "title": "L",
          "steps": [{"kind": "show", "structure": "cochlea", "preset": "p", "view": "superior", "title": "t",
          "text": "x"}]}], "exams": [)";
  const auto parse = [&](const std::string& exam) { return parseCourseJson(head + exam + "]}", "c.json"); };
  auto ok = parse(R"({"id": "c.exam", "title": "Exam", "structures": ["cochlea", "stapes"],
                      "kinds": ["locate", "name"], "count": 3, "time_limit_s": 300, "locate_views": ["slice"],
                      "pass_score": 0.7, "prerequisites": ["l"]})");
  REQUIRE_MESSAGE(ok, (ok ? "" : ok.error().message));
  REQUIRE(ok->exams.size() == 1);
  const ExamSpec& e = ok->exams[0];
  CHECK(e.count == 3);
  CHECK(e.timeLimitS == 300);
  CHECK((e.locateViews == std::vector<ExamLocateView>{ExamLocateView::Slice}));
  CHECK(e.passScore == std::optional<double>(0.7));
  // Round trip through the writer.
  auto back = parseCourseJson(courseToJson(*ok), "back.json");
  REQUIRE(back);
  CHECK(courseToJson(*back) == courseToJson(*ok));

  const std::map<std::string, std::string> mistakes = {
      {R"({"id": "x", "title": "T", "structures": ["cochlea"], "kinds": ["name"], "count": 2, "time_limit_s": 60})",
       "c.json: exams[0].count: must be 1..1"},
      {R"({"id": "x", "title": "T", "structures": ["cochlea"], "kinds": ["order"], "count": 1, "time_limit_s": 60})",
       "c.json: exams[0].kinds[0]: exams draw locate, identify and name items only"},
      {R"({"id": "x", "title": "T", "structures": [], "kinds": ["name"], "count": 1, "time_limit_s": 60})",
       "c.json: exams[0].structures: needs at least one"},
      {R"({"id": "x", "title": "T", "structures": ["a", "a"], "kinds": ["name"], "count": 1, "time_limit_s": 60})",
       "c.json: exams[0].structures[1]: 'a' is listed twice"},
      {R"({"id": "x", "title": "T", "structures": ["a"], "kinds": ["name"], "count": 1})",
       "c.json: exams[0].time_limit_s: missing"},
      {R"({"id": "x", "title": "T", "structures": ["a"], "kinds": ["name"], "count": 1, "time_limit_s": 0})",
       "c.json: exams[0].time_limit_s: must be 1..86400"},
      {R"({"id": "x", "title": "T", "structures": ["a"], "kinds": ["name"], "count": 1, "time_limit_s": 9, "locate_views": ["3d"]})",
       "c.json: exams[0].locate_views: only used by locate items"},
      {R"({"id": "x", "title": "T", "structures": ["a"], "kinds": ["locate"], "count": 1, "time_limit_s": 9, "locate_views": ["mri"]})",
       "c.json: exams[0].locate_views[0]: unknown locate view 'mri'"},
      {R"({"id": "x", "title": "T", "structures": ["a"], "kinds": ["name"], "count": 1, "time_limit_s": 9, "pass_score": 70})",
       "c.json: exams[0].pass_score: must be a share of 0..1"},
      {R"({"id": "l", "title": "T", "structures": ["a"], "kinds": ["name"], "count": 1, "time_limit_s": 9})",
       "c.json: exams[0].id: 'l' is already a lesson or exam id"},
      {R"({"id": "x", "title": "T", "structures": ["a"], "kinds": ["name"], "count": 1, "time_limit_s": 9, "prerequisites": ["zz"]})",
       "c.json: exams[0].prerequisites[0]: 'zz' is not a lesson of this course"},
      {R"({"id": "x", "title": "T", "structures": ["a"], "kinds": ["name"], "count": 1, "time_limit_s": 9, "minutes": 3})",
       "c.json: exams[0].minutes: unknown field"},
  };
  for (const auto& [exam, message] : mistakes) {
    CAPTURE(exam);
    auto r = parse(exam);
    REQUIRE_FALSE(r);
    CHECK(r.error().message.find(message) == 0);
  }
}
