// Instructor analytics on a synthetic class of 50 students stored in a real SQLite file: lesson,
// review and exam answers, attempts, FSRS memory states. Every figure the analytics report is
// recomputed here from the events as they were generated (the Elo replay with U(n) included), and
// the CSV of `anatomy-tutor analytics` carries the same numbers.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "db/analytics_store.h"
#include "db/course_store.h"
#include "db/exam_store.h"
#include "lessons/analytics.h"
#include "lessons/scheduling.h"
#include "quiz/elo.h"
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"

using namespace at;
using namespace at::lessons;

namespace {

constexpr UnixSeconds kStart = 1'700'000'000;
constexpr UnixSeconds kDay = 86400;

// One generated answer, as the test remembers it.
struct Event {
  std::int64_t user = 0;
  std::string question, structure;
  double score = 0;
  bool correct = false;
  UnixSeconds at = 0;
  int sequence = 0;  // the order events were recorded in
};

struct ClassFixture {
  test::TempDir dir{"analytics"};
  std::string path = test::freshDatabase(dir, "class.db");
  Course course = test::toyCourse();
  std::vector<User> students;
  std::vector<Event> events;
  std::map<std::pair<std::int64_t, std::string>, StructureProgress> memory;
  std::map<std::int64_t, std::set<std::string>> started, finished;
  std::map<std::pair<std::int64_t, std::string>, double> bestScore;
  std::map<std::int64_t, double> examScore;  // latest finished
  std::vector<std::pair<double, bool>> examResults;  // score, passed
  UnixSeconds now = 0;
};

// The course's questions as (id, target, kind, lesson), in order.
struct Q {
  std::string id, target, lesson;
  quiz::QuestionKind kind;
};

std::vector<Q> questionsOf(const Course& c) {
  std::vector<Q> out;
  for (const Lesson& l : c.lessons)
    for (const Step& s : l.steps)
      if (s.kind == StepKind::Question) out.push_back({s.question.id, s.question.target, l.id, s.question.kind});
  return out;
}

void buildClass(ClassFixture& f, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  ExamSpec exam;
  exam.id = "toy.exam";
  exam.title = "Toy exam";
  exam.structures = {"stapes", "incus", "malleus"};
  exam.kinds = {quiz::QuestionKind::Name};
  exam.count = 3;
  exam.timeLimitS = 600;
  exam.passScore = 0.6;
  f.course.exams = {exam};
  auto database = db::Database::open(f.path);
  REQUIRE(database);
  REQUIRE(db::storeCourse(*database, f.course, "test"));
  db::SqlUserRepository users(*database);
  db::SqlProgressRepository progress(*database);
  db::SqlExamRepository exams(*database);
  const Fsrs fsrs;
  const auto questions = questionsOf(f.course);
  int sequence = 0;

  // Records one graded answer through the repository the app uses, and remembers it.
  const auto answer = [&](std::int64_t user, const std::string& question, const std::string& structure,
                          quiz::QuestionKind kind, bool correct, double score, UnixSeconds at,
                          const std::function<void(const GradedAnswer&, const LearnerUpdate&)>& store) {
    GradedAnswer g;
    g.questionId = question;
    g.structureId = structure;
    g.answer.text = "x";
    g.correct = correct;
    g.score = score;
    g.latencyMs = 3000;
    g.answeredAt = at;
    const StructureProgress before = f.memory.count({user, structure}) ? f.memory[{user, structure}]
                                                                        : StructureProgress{.userId = user, .structureId = structure, .memory = {}};
    LearnerUpdate up;
    up.rating = ratingFor(correct, score, kind, g.latencyMs);
    up.memoryBefore = before.memory;
    up.progress = scheduleAnswer(before, up.rating, correct, at, fsrs);
    store(g, up);
    f.memory[{user, structure}] = up.progress;
    f.events.push_back({user, question, structure, score, correct, at, sequence++});
  };

  for (int s = 0; s < 50; ++s) {
    auto user = users.createUser("student" + std::to_string(100 + s), Role::Student, s % 2 ? "B" : "A");
    REQUIRE(user);
    f.students.push_back(*user);
    const double skill = u(rng);
    UnixSeconds clock = kStart + s * 600;
    for (const Lesson& lesson : f.course.lessons) {
      if (u(rng) < 0.15) break;  // stops before this lesson (and the next)
      auto attempt = progress.startAttempt(user->id, lesson.id, LessonMode::Guided, clock);
      REQUIRE(attempt);
      f.started[user->id].insert(lesson.id);
      double total = 0;
      int asked = 0;
      bool quit = false;
      for (std::size_t i = 0; i < lesson.steps.size(); ++i) {
        const Step& step = lesson.steps[i];
        if (step.kind != StepKind::Question) continue;
        if (u(rng) < 0.05) {
          quit = true;
          break;
        }
        const bool correct = u(rng) < 0.3 + 0.6 * skill;
        const double score = correct ? 1.0 : (step.question.kind == quiz::QuestionKind::Order && u(rng) < 0.5 ? 0.5 : 0.0);
        clock += 45;
        answer(user->id, step.question.id, step.question.target, step.question.kind, correct, score, clock,
               [&](const GradedAnswer& g, const LearnerUpdate& up) {
                 AnswerRecord r;
                 static_cast<GradedAnswer&>(r.response) = g;
                 r.response.attemptId = attempt->id;
                 r.response.stepIndex = int(i);
                 r.update = up;
                 REQUIRE(progress.recordAnswer(r));
               });
        total += score;
        ++asked;
      }
      if (quit) break;
      REQUIRE(progress.finishAttempt(attempt->id, clock + 10, total / asked));
      f.finished[user->id].insert(lesson.id);
      auto& best = f.bestScore[{user->id, lesson.id}];
      best = std::max(best, total / asked);
    }
    // Some come back for a review of a structure they answered, days later.
    if (!f.started[user->id].empty() && u(rng) < 0.6) {
      const Q& q = questions[0];  // toy.ossicles.name_stapes
      if (f.memory.count({user->id, q.target})) {
        const bool correct = u(rng) < 0.5 + 0.4 * skill;
        answer(user->id, q.id, q.target, q.kind, correct, correct ? 1 : 0, clock + 3 * kDay,
               [&](const GradedAnswer& g, const LearnerUpdate& up) {
                 ReviewRecord r;
                 static_cast<GradedAnswer&>(r.response) = g;
                 r.response.userId = user->id;
                 r.update = up;
                 REQUIRE(progress.recordReviewAnswer(r));
               });
      }
    }
    // Half take the exam.
    if (u(rng) < 0.5) {
      ExamAttempt a;
      a.userId = user->id;
      a.examId = exam.id;
      a.courseId = f.course.id;
      a.startedAt = clock + 4 * kDay;
      a.deadline = a.startedAt + 600;
      std::vector<ExamItem> items(3);
      for (int i = 0; i < 3; ++i) {
        items[std::size_t(i)].position = i;
        items[std::size_t(i)].question.question.id = exam.id + ".name." + exam.structures[std::size_t(i)];
        items[std::size_t(i)].question.question.kind = quiz::QuestionKind::Name;
        items[std::size_t(i)].question.question.target = exam.structures[std::size_t(i)];
        items[std::size_t(i)].question.question.prompt = "Name the marked structure.";
      }
      auto started = exams.startExamAttempt(a, items);
      REQUIRE(started);
      double total = 0;
      for (int i = 0; i < 3; ++i) {
        const bool correct = u(rng) < 0.2 + 0.7 * skill;
        answer(user->id, items[std::size_t(i)].question.question.id, exam.structures[std::size_t(i)],
               quiz::QuestionKind::Name, correct, correct ? 1 : 0, a.startedAt + 60 * (i + 1),
               [&](const GradedAnswer& g, const LearnerUpdate& up) {
                 ExamAnswerRecord r;
                 r.attemptId = started->id;
                 r.position = i;
                 r.answer = g;
                 r.update = up;
                 REQUIRE(exams.recordExamAnswer(r));
               });
        total += correct ? 1 : 0;
      }
      const double score = total / 3;
      REQUIRE(exams.finishExamAttempt(started->id, a.startedAt + 300, score, score >= 0.6));
      f.examScore[user->id] = score;
      f.examResults.push_back({score, score >= 0.6});
    }
  }
  f.now = kStart + 20 * kDay;
}

}  // namespace

TEST_CASE("Analytics of a synthetic class of 50 students match the figures recomputed from its events") {
  ClassFixture f;
  buildClass(f, test::freshSeed("Analytics_SyntheticClass"));
  auto database = db::Database::open(f.path);
  REQUIRE(database);
  db::SqlCurriculumRepository curriculum(*database, test::toyBuiltin());
  auto input = db::loadAnalyticsInput(*database, curriculum, "toy", std::nullopt);
  REQUIRE_MESSAGE(input, (input ? "" : input.error().message));
  CHECK(input->students.size() == 50);
  CHECK(input->answers.size() == f.events.size());
  const ClassAnalytics a = computeAnalytics(*input, f.now);
  CHECK(a.classSize == 50);
  CHECK(a.answers == int(f.events.size()));

  // Completion per lesson: finished / 50, and the mean best score of those who finished.
  REQUIRE(a.lessons.size() == 2);
  for (const LessonCompletion& l : a.lessons) {
    CAPTURE(l.lessonId);
    int started = 0, finished = 0;
    double best = 0;
    for (const User& s : f.students) {
      started += f.started[s.id].count(l.lessonId) ? 1 : 0;
      if (f.finished[s.id].count(l.lessonId)) {
        ++finished;
        best += f.bestScore[{s.id, l.lessonId}];
      }
    }
    CHECK(l.started == started);
    CHECK(l.finished == finished);
    CHECK(l.completion == doctest::Approx(finished / 50.0));
    if (finished) CHECK(*l.meanBestScore == doctest::Approx(best / finished));
    CHECK(l.scoresUnknown == 0);  // every end on one machine is scored when it ends
  }

  // Question difficulty: Elo with U(n) = 1/(1 + 0.05 n), replayed here over the events in order.
  std::vector<Event> ordered = f.events;
  std::stable_sort(ordered.begin(), ordered.end(), [](const Event& x, const Event& y) { return x.at < y.at; });
  std::map<std::string, double> difficulty;
  std::map<std::string, int> nQuestion, nRight;
  std::map<std::int64_t, double> ability;
  std::map<std::int64_t, int> nStudent;
  for (const auto& q : questionsOf(f.course)) difficulty[q.id] = 1500;
  const double k = 400 / std::log(10.0);
  for (const Event& e : ordered) {
    if (!difficulty.count(e.question)) difficulty[e.question] = 1500;
    if (!ability.count(e.user)) ability[e.user] = 1500;
    const double expected = 1 / (1 + std::pow(10, (difficulty[e.question] - ability[e.user]) / 400));
    const double delta = e.score - expected;
    ability[e.user] += k / (1 + 0.05 * nStudent[e.user]++) * delta;
    difficulty[e.question] -= k / (1 + 0.05 * nQuestion[e.question]++) * delta;
    nRight[e.question] += e.correct ? 1 : 0;
  }
  CHECK(a.questions.size() == difficulty.size());
  for (const QuestionStats& q : a.questions) {
    CAPTURE(q.questionId);
    CHECK(q.answers == nQuestion[q.questionId]);
    CHECK(q.correct == nRight[q.questionId]);
    CHECK(q.difficulty == doctest::Approx(difficulty[q.questionId]).epsilon(1e-9));
  }
  for (std::size_t i = 1; i < a.questions.size(); ++i) CHECK(a.questions[i - 1].difficulty >= a.questions[i].difficulty);

  // The items most missed: by answers not right (most first), then by their share, then by id.
  std::vector<std::tuple<int, double, std::string>> missedHere;
  for (const auto& [id, n] : nQuestion)
    if (n > nRight[id]) missedHere.emplace_back(-(n - nRight[id]), double(nRight[id]) / n, id);
  std::sort(missedHere.begin(), missedHere.end());
  const auto missed = mostMissed(a, 4);
  REQUIRE(missed.size() == std::min<std::size_t>(4, missedHere.size()));
  REQUIRE_FALSE(missed.empty());
  for (std::size_t i = 0; i < missed.size(); ++i) {
    CHECK(missed[i].questionId == std::get<2>(missedHere[i]));
    CHECK(missed[i].answers - missed[i].correct == -std::get<0>(missedHere[i]));
  }
  CHECK(mostMissed(a, 1000).size() == missedHere.size());

  // Hardest structures: share of right answers, lowest first, and the class's mean FSRS state.
  const Fsrs fsrs;
  for (const StructureStats& s : a.structures) {
    CAPTURE(s.structureId);
    int answers = 0, right = 0, students = 0;
    double d = 0, recall = 0;
    for (const Event& e : f.events)
      if (e.structure == s.structureId) ++answers, right += e.correct ? 1 : 0;
    for (const auto& [key, p] : f.memory)
      if (key.second == s.structureId) ++students, d += p.memory.difficulty, recall += fsrs.retrievability(p.memory, f.now);
    CHECK(s.answers == answers);
    CHECK(s.correctShare == doctest::Approx(double(right) / answers));
    CHECK(s.students == students);
    CHECK(s.meanDifficulty == doctest::Approx(d / students));
    CHECK(s.meanRecall == doctest::Approx(recall / students));
  }
  for (std::size_t i = 1; i < a.structures.size(); ++i) CHECK(a.structures[i - 1].correctShare <= a.structures[i].correctShare);

  // Predicted recall per student: the mean retrievability now over the structures taught (targets
  // of questions in lessons started, with a memory state); the exam's latest score.
  REQUIRE(a.students.size() == 50);
  for (const StudentRecall& s : a.students) {
    CAPTURE(s.name);
    std::set<std::string> asked;
    for (const auto& q : questionsOf(f.course))
      if (f.started[s.userId].count(q.lesson)) asked.insert(q.target);
    int taught = 0, due = 0;
    double sum = 0;
    for (const auto& [key, p] : f.memory)
      if (key.first == s.userId && asked.count(key.second)) {
        ++taught;
        sum += fsrs.retrievability(p.memory, f.now);
        due += p.memory.due <= f.now ? 1 : 0;
      }
    CHECK(s.taught == taught);
    CHECK(s.due == due);
    if (taught) CHECK(*s.meanRecall == doctest::Approx(sum / taught));
    else CHECK_FALSE(s.meanRecall.has_value());
    CHECK(s.lessonsFinished == int(f.finished[s.userId].size()));
    if (f.examScore.count(s.userId)) CHECK(*s.examScore == doctest::Approx(f.examScore[s.userId]));
    else CHECK_FALSE(s.examScore.has_value());
  }

  // Exams: attempts, mean score, pass rate.
  REQUIRE(a.exams.size() == 1);
  double sum = 0;
  int passed = 0;
  for (const auto& [score, pass] : f.examResults) sum += score, passed += pass ? 1 : 0;
  CHECK(a.exams[0].attempts == int(f.examResults.size()));
  if (!f.examResults.empty()) {
    CHECK(*a.exams[0].meanScore == doctest::Approx(sum / f.examResults.size()));
    CHECK(*a.exams[0].passRate == doctest::Approx(double(passed) / f.examResults.size()));
  }

  // A group is a smaller class.
  auto groupA = db::loadAnalyticsInput(*database, curriculum, "toy", std::string("A"));
  REQUIRE(groupA);
  CHECK(computeAnalytics(*groupA, f.now).classSize == 25);
  CHECK_FALSE(db::loadAnalyticsInput(*database, curriculum, "nope", std::nullopt));

  // The command prints the same figures as CSV (long form on stdout).
  if (!test::requireAppBinary("analytics --csv")) return;
  const auto csv = test::runApp("analytics toy --csv --db '" + f.path + "'");
  INFO(csv.err);
  REQUIRE(csv.exitCode == 0);
  CHECK(csv.out.rfind("table,id,name,metric,value\n", 0) == 0);
  const auto& hardest = a.questions.front();
  char line[256];
  std::snprintf(line, sizeof line, "questions,%s,%s,elo_difficulty,%.2f\n", hardest.questionId.c_str(), hardest.lessonId.c_str(),
                difficulty[hardest.questionId]);
  CHECK(csv.out.find(line) != std::string::npos);
  std::snprintf(line, sizeof line, "lessons,toy.ossicles,Ossicles,completion,%.4f\n", a.lessons[0].completion);
  CHECK(csv.out.find(line) != std::string::npos);
  const auto wide = test::runApp("analytics toy --csv --out '" + (f.dir / "csv").string() + "' --db '" + f.path + "'");
  REQUIRE(wide.exitCode == 0);
  const std::string students = test::readFile(f.dir / "csv" / "students.csv");
  CHECK(std::count(students.begin(), students.end(), '\n') == 51);
  CHECK(students.rfind("student,group,taught,due,mean_recall,", 0) == 0);
  // The review log for an FSRS optimiser: one row per answer, ratings 1..4, times in ms.
  const std::string revlog = test::readFile(f.dir / "csv" / "revlog.csv");
  CHECK(std::count(revlog.begin(), revlog.end(), '\n') == long(f.events.size()) + 1);
  CHECK(revlog.rfind("card_id,student,structure,review_time,review_rating,review_state,review_duration\n", 0) == 0);
  // Text people typed is guarded against spreadsheet formulas (quiz::csvCell); numbers, negative
  // ones included, stay numbers: a student named like a formula in a group "-A", and one review
  // logged before 1970 (a negative review_time).
  {
    db::SqlUserRepository users(*database);
    REQUIRE(users.createUser("=HYPERLINK(\"http://example.org\",\"x\")", Role::Student, "-A"));
    REQUIRE(database->exec("UPDATE review_log SET reviewed_at = -86400 WHERE id = (SELECT min(id) FROM review_log)"));
  }
  const auto guarded = test::runApp("analytics toy --csv --out '" + (f.dir / "guarded").string() + "' --db '" + f.path + "'");
  REQUIRE_MESSAGE(guarded.exitCode == 0, guarded.err);
  const std::string guardedStudents = test::readFile(f.dir / "guarded" / "students.csv");
  CHECK(guardedStudents.find("\"'=HYPERLINK(\"\"http://example.org\"\",\"\"x\"\")\",'-A,0,0,,,,0,\n") != std::string::npos);
  const std::string guardedLog = test::readFile(f.dir / "guarded" / "revlog.csv");
  CHECK(guardedLog.find(",-86400000,") != std::string::npos);
  CHECK(guardedLog.find("'-") == std::string::npos);
  const auto guardedLong = test::runApp("analytics toy --csv --db '" + f.path + "'");
  REQUIRE(guardedLong.exitCode == 0);
  CHECK(guardedLong.out.find("students,\"'=HYPERLINK(\"\"http://example.org\"\",\"\"x\"\")\",'-A,taught,0\n") != std::string::npos);
  const auto occurrences = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  CHECK(occurrences(guardedLong.out, "'-") == occurrences(guardedLong.out, ",'-A,"));  // the group only, no number
  CHECK(occurrences(guardedLong.out, ",'-A,") == 7);  // one per metric of the students table
  const auto text = test::runApp("analytics toy --db '" + f.path + "'");
  REQUIRE(text.exitCode == 0);
  CHECK(text.out.find("class of 51 students") != std::string::npos);  // with the one named like a formula
  CHECK(text.out.find("Hardest structures") != std::string::npos);
  CHECK(test::runApp("analytics nope --db '" + f.path + "'").exitCode != 0);
}

TEST_CASE("Analytics: an end whose score is not known yet counts as finished, never as a score of 0") {
  AnalyticsInput in;
  in.course.id = "toy";
  in.course.lessons.push_back(Lesson{});
  in.course.lessons.back().id = "ossicles";
  for (std::int64_t id : {1, 2, 3}) in.students.push_back(User{id, "s" + std::to_string(id), Role::Student, ""});
  const auto end = [&](std::int64_t user, std::optional<double> score) {
    Attempt a;
    a.id = std::int64_t(in.attempts.size()) + 1;
    a.userId = user;
    a.lessonId = "ossicles";
    a.startedAt = 100;
    a.finishedAt = 200;
    a.score = score.value_or(0.0);
    a.scoreKnown = score.has_value();
    in.attempts.push_back(a);
  };
  end(1, 0.5);
  end(1, std::nullopt);  // a later run still waiting: her best known score stays 0.5
  end(2, std::nullopt);  // finished, nothing scored yet
  end(3, 1.0);
  const ClassAnalytics a = computeAnalytics(in, 300);
  REQUIRE(a.lessons.size() == 1);
  CHECK(a.lessons[0].finished == 3);
  CHECK(a.lessons[0].scoresUnknown == 1);
  REQUIRE(a.lessons[0].meanBestScore);
  CHECK(*a.lessons[0].meanBestScore == doctest::Approx(0.75));
}
