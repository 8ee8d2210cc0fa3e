// The learning commands through the real anatomy-tutor binary: every shipped lesson played from
// answers computed from its keys, kill -9 in the middle of a lesson and resume, concurrent
// players, malformed answer lines, and a real abdominal course on the TotalSegmentator sample.
#include <doctest/doctest.h>

#include <cstring>

#include <cstdlib>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sys/stat.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "db/course_store.h"
#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "lessons/course_json.h"
#include "quiz/answer_json.h"
#include "quiz/keys.h"
#include "quiz/name_matching.h"
#include "test_databases.h"
#include "skull_scan.h"
#include "test_support.h"
#include "toy_play.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"
#include "volume/phantom.h"
#include "wdt/answer_keys.h"

namespace fs = std::filesystem;
using namespace at;

namespace {

bool appAvailable() {
  if (fs::exists(test::appBinary())) return true;
  at::test::skipf("%s is not built", test::appBinary().c_str());
  return false;
}

std::int64_t scalar(const std::string& dbPath, const std::string& sql) {
  auto db = db::Database::open(dbPath);
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  auto s = db->prepare(sql);
  REQUIRE_MESSAGE(s, (s ? "" : s.error().message));
  auto row = s->step();
  REQUIRE(row);
  REQUIRE(*row);
  return s->int64(0);
}

// The app's answer keys: the one recipe of wdt/answer_keys.h.
quiz::DistanceFieldFunction answerKeyFields(const Dataset& dataset) {
  return [&dataset](const Mask& seeds) { return wdt::answerKeyDistances(dataset.volume, dataset.labels.geometry, seeds); };
}

// The right answer to a resolved question, as an answers-file line.
std::string rightAnswerLine(const quiz::ResolvedQuestion& q, const std::vector<Structure>& structures) {
  return quiz::answerToJson(test::rightAnswer(q, structures));
}

// Answers files for every lesson of `course`, from keys computed on `dataset`.
std::map<std::string, std::vector<std::string>> answersFor(const lessons::Course& course, const Dataset& dataset) {
  quiz::DatasetKeyComputer keys(dataset, answerKeyFields(dataset));
  std::map<std::string, std::vector<std::string>> out;
  for (const auto& lesson : course.lessons) {
    auto& lines = out[lesson.id];
    for (const auto& step : lesson.steps) {
      if (step.kind != lessons::StepKind::Question) continue;
      auto resolved = quiz::resolveQuestion(step.question, keys);
      REQUIRE_MESSAGE(resolved, (resolved ? "" : resolved.error().message));
      lines.push_back(rightAnswerLine(*resolved, dataset.structures));
    }
  }
  return out;
}

fs::path writeLines(const fs::path& path, const std::vector<std::string>& lines) {
  std::ofstream f(path);
  for (const auto& l : lines) f << l << "\n";
  return path;
}

// A quick course on the phantom whose keys need no distance field (no volume is built).
lessons::Course quickCourse() {
  lessons::Course c;
  c.id = "quick";
  c.title = "Quick ear check";
  c.datasetId = "phantom";
  const auto structures = phantomStructures();
  REQUIRE(structures.size() >= 4);
  lessons::Lesson l;
  l.id = "quick.check";
  l.courseId = c.id;
  l.title = "Quick check";
  lessons::Step show;
  show.kind = lessons::StepKind::Show;
  show.show.structure = structures[0].id;
  show.show.presetId = "default_wdt";
  show.show.title = "Look";
  show.show.text = "Look at it.";
  l.steps.push_back(show);
  for (int i = 0; i < 6; ++i) {
    const Structure& target = structures[std::size_t(i % 4)];
    lessons::Step step;
    step.kind = lessons::StepKind::Question;
    quiz::Question& q = step.question;
    q.id = "quick.check.q" + std::to_string(i);
    q.target = target.id;
    q.prompt = "Question " + std::to_string(i) + " about " + target.id;
    if (i % 3 == 0) {
      q.kind = quiz::QuestionKind::Name;
    } else if (i % 3 == 1) {
      q.kind = quiz::QuestionKind::Locate;
    } else {
      q.kind = quiz::QuestionKind::Identify;
      q.choices = {structures[0].id, structures[1].id, structures[2].id, structures[3].id};
    }
    l.steps.push_back(step);
  }
  c.lessons.push_back(l);
  return c;
}

// Right answers for quickCourse(): its identify choices are listed, so no keys are needed.
std::vector<std::string> quickAnswers() {
  const auto structures = phantomStructures();
  std::vector<std::string> lines;
  const lessons::Course course = quickCourse();
  for (const auto& step : course.lessons[0].steps) {
    if (step.kind != lessons::StepKind::Question) continue;
    quiz::ResolvedQuestion r;
    r.question = step.question;
    r.choices = step.question.choices;
    for (std::size_t i = 0; i < r.choices.size(); ++i)
      if (r.choices[i] == step.question.target) r.keyChoice = int(i);
    lines.push_back(rightAnswerLine(r, structures));
  }
  return lines;
}

void storeQuickCourse(const std::string& dbPath) {
  auto db = db::Database::open(dbPath);
  REQUIRE(db);
  auto stored = db::storeCourse(*db, quickCourse(), "test");
  REQUIRE_MESSAGE(stored, (stored ? "" : stored.error().message));
}

std::string playArgs(const std::string& lesson, const std::string& user, const fs::path& answers,
                     const std::string& dbPath) {
  return "play " + lesson + " --user " + user + " --new-user --no-views --answers '" + answers.string() + "' --db '" +
         dbPath + "'";
}

// Plays every lesson of `course` in teaching order (which satisfies the prerequisites) as `user`
// with answers computed from its keys on `dataset`: each scores 1.00, and `answered` (the responses
// stored in `dbPath` so far) grows by its questions.
void playEveryLesson(const lessons::Course& course, const Dataset& dataset, const test::TempDir& dir, const std::string& user,
                     const std::string& dbPath, int& answered) {
  const auto answers = answersFor(course, dataset);
  for (const auto& lesson : course.lessons) {
    CAPTURE(lesson.id);
    const fs::path answersFile = writeLines(dir / (lesson.id + ".jsonl"), answers.at(lesson.id));
    auto r = test::runApp(playArgs(lesson.id, user, answersFile, dbPath));
    CHECK_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.out.find("right (score 1.00).") != std::string::npos);
    answered += int(answers.at(lesson.id).size());
    CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == answered);
  }
}

}  // namespace

TEST_CASE("Every shipped lesson plays to the end from answers computed from the course's keys") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "shipped.db");
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(test::sourceDir() / "data" / "courses"))
    if (e.path().extension() == ".json") files.push_back(e.path());
  REQUIRE(!files.empty());
  std::sort(files.begin(), files.end());
  int questions = 0;  // answered so far, over all courses
  for (const auto& file : files) {
    CAPTURE(file);
    auto course = lessons::loadCourseJson(file);
    REQUIRE_MESSAGE(course, (course ? "" : course.error().message));
    // Shipped courses use the built-in phantom or a known scan (the skull CT, its labels grown from
    // the kept seeds; skipped where it could not be fetched).
    std::optional<test::SkullCacheScope> scope;
    Result<Dataset> dataset = fail("");
    if (const KnownScan* scan = findKnownScan(course->datasetId)) {
      const auto& cache = test::grownSkullCache();
      if (!cache) continue;
      scope.emplace(*cache);
      dataset = openKnownScan(*scan);
    } else {
      REQUIRE(isBuiltinDatasetName(course->datasetId));
      dataset = openBuiltinDataset(course->datasetId);
    }
    REQUIRE_MESSAGE(dataset, test::errorText(dataset));
    playEveryLesson(*course, *dataset, dir, "student", dbPath, questions);
    CHECK(scalar(dbPath, "SELECT count(*) FROM responses WHERE correct = 0") == 0);
    CHECK(scalar(dbPath, "SELECT count(*) FROM attempts WHERE finished_at IS NULL") == 0);
  }
  auto progress = test::runApp("progress --user student --db '" + dbPath + "'");
  CHECK_MESSAGE(progress.exitCode == 0, progress.err);
  CHECK(progress.out.find("finished, best score 1.00") != std::string::npos);
  CHECK(progress.out.find("Due for review now: nothing") != std::string::npos);
}

TEST_CASE("play killed with SIGKILL mid-lesson keeps every answer and resumes at the next step") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "crash.db");
  storeQuickCourse(dbPath);
  const auto answers = quickAnswers();
  const int answeredBeforeKill = 4;

  const fs::path fifo = dir / "answers.fifo";
  REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    const int devnull = open("/dev/null", O_WRONLY);
    dup2(devnull, 1);
    dup2(devnull, 2);
    const std::string app = test::appBinary().string();
    execl(app.c_str(), app.c_str(), "play", "quick.check", "--user", "eve", "--new-user", "--no-views", "--answers", fifo.c_str(),
          "--db", dbPath.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const int out = open(fifo.c_str(), O_WRONLY);  // waits for play to open its end
  REQUIRE(out >= 0);
  const auto countResponses = [&] { return scalar(dbPath, "SELECT count(*) FROM responses"); };
  for (int i = 0; i < answeredBeforeKill; ++i) {
    const std::string line = answers[std::size_t(i)] + "\n";
    REQUIRE(write(out, line.data(), line.size()) == ssize_t(line.size()));
    // Wait until play has committed this answer (it then waits for the next line).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (countResponses() < i + 1 && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    REQUIRE(countResponses() == i + 1);
  }
  REQUIRE(kill(child, SIGKILL) == 0);
  int status = 0;
  REQUIRE(waitpid(child, &status, 0) == child);
  CHECK(WIFSIGNALED(status));
  close(out);

  CHECK(countResponses() == answeredBeforeKill);
  CHECK(scalar(dbPath, "SELECT count(*) FROM attempts WHERE finished_at IS NULL") == 1);

  const fs::path rest = writeLines(dir / "rest.jsonl", {answers.begin() + answeredBeforeKill, answers.end()});
  auto r = test::runApp(playArgs("quick.check", "eve", rest, dbPath));
  CHECK_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("resuming attempt") != std::string::npos);
  // The first step shown after resuming is the fifth question (step 6 of 7: one show step first).
  const auto firstStep = r.out.find("\n[");
  REQUIRE(firstStep != std::string::npos);
  CHECK(r.out.compare(firstStep, 7, "\n[6/7] ") == 0);
  // No question answered before the kill is asked again; the end-of-lesson review lists them all.
  const std::string asked = r.out.substr(0, r.out.find("\nReview:"));
  CHECK(asked.find("Question 0 about") == std::string::npos);
  CHECK(r.out.find("\nReview:") != std::string::npos);
  CHECK(r.out.find("Question 0 about", asked.size()) != std::string::npos);
  CHECK(r.out.find("right (score 1.00).") != std::string::npos);
  CHECK(countResponses() == std::int64_t(answers.size()));
  CHECK(scalar(dbPath, "SELECT count(DISTINCT step_index) FROM responses") == std::int64_t(answers.size()));
  CHECK(scalar(dbPath, "SELECT count(*) FROM attempts") == 1);
  CHECK(scalar(dbPath, "SELECT count(*) FROM attempts WHERE finished_at IS NOT NULL") == 1);
}

TEST_CASE("Four play processes recording into one database at once lose nothing") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "many.db");
  storeQuickCourse(dbPath);
  const auto answers = quickAnswers();
  const fs::path file = writeLines(dir / "a.jsonl", answers);
  constexpr int kPlayers = 4;
  std::vector<std::thread> players;
  std::vector<test::CommandResult> results(kPlayers);
  for (int i = 0; i < kPlayers; ++i)
    players.emplace_back([&, i] { results[std::size_t(i)] = test::runApp(playArgs("quick.check", "p" + std::to_string(i), file, dbPath)); });
  for (auto& t : players) t.join();
  for (const auto& r : results) CHECK_MESSAGE(r.exitCode == 0, r.err);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == kPlayers * std::int64_t(answers.size()));
  CHECK(scalar(dbPath, "SELECT count(*) FROM users") == kPlayers);
  CHECK(scalar(dbPath, "SELECT sum(answered) FROM question_stats") == kPlayers * std::int64_t(answers.size()));
}

TEST_CASE("A malformed answers line is reported with its number and reason, earlier answers kept") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "bad.db");
  storeQuickCourse(dbPath);
  const auto answers = quickAnswers();

  const fs::path broken = writeLines(dir / "broken.jsonl", {answers[0], "", "{\"choice\": "});
  auto r = test::runApp(playArgs("quick.check", "fay", broken, dbPath));
  CHECK(r.exitCode != 0);
  INFO(r.err);
  CHECK(r.err.find("broken.jsonl:3: column 12, field 'choice': not valid JSON") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == 1);

  // An answer of the wrong kind for the question (a choice for a locate question) names its line.
  const fs::path wrongKind = writeLines(dir / "wrong.jsonl", {"{\"choice\": 1}"});
  auto w = test::runApp(playArgs("quick.check", "fay", wrongKind, dbPath));
  CHECK(w.exitCode != 0);
  CHECK(w.err.find("wrong.jsonl:1: ") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == 1);

  const fs::path unknownField = writeLines(dir / "field.jsonl", {"{\"pick\": \"x\", \"colour\": 3}"});
  auto u = test::runApp(playArgs("quick.check", "fay", unknownField, dbPath));
  CHECK(u.exitCode != 0);
  CHECK(u.err.find("field.jsonl:1: ") != std::string::npos);
  CHECK(u.err.find("colour") != std::string::npos);
}

TEST_CASE("Unknown lessons and users get a clear message") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "u.db");
  auto lesson = test::runApp("play no_such_lesson --user zoe --new-user --db '" + dbPath + "'");
  CHECK(lesson.exitCode != 0);
  CHECK(lesson.err.find("unknown lesson 'no_such_lesson'") != std::string::npos);
  auto user = test::runApp("play inner_ear --user nobody --db '" + dbPath + "'");
  CHECK(user.exitCode != 0);
  CHECK(user.err.find("unknown user 'nobody'") != std::string::npos);
  auto progress = test::runApp("progress --user nobody --db '" + dbPath + "'");
  CHECK(progress.exitCode != 0);
  CHECK(progress.err.find("unknown user 'nobody'") != std::string::npos);
}

TEST_CASE("Interactive play takes typed answers on stdin and stops cleanly at 'quit'") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "i.db");
  storeQuickCourse(dbPath);
  const auto structures = phantomStructures();
  // Question 0 is a name question: type the display name; then quit at question 1.
  auto r = test::runApp("play quick.check --user gus --new-user --no-views --db '" + dbPath + "'",
                        structures[0].displayName + "\nquit\n");
  CHECK_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("✓ Correct") != std::string::npos);
  CHECK(r.out.find("run the same command to resume") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == 1);
  // A locate question: a name is no answer (it would give the answer away), nonsense neither; a
  // point in millimetres inside the structure is graded, without pictures too.
  auto phantom = openBuiltinDataset("phantom:128");
  REQUIRE(phantom);
  const Structure* target = phantom->findStructure(structures[1].id);
  REQUIRE(target);
  std::optional<Vec3> inside;
  const Dims& d = phantom->labels.dims();
  for (int k = d.z / 4; k < d.z && !inside; ++k)
    for (int j = 0; j < d.y && !inside; ++j)
      for (int i = 0; i < d.x && !inside; ++i)
        if (phantom->labels.at(i, j, k) == target->label)
          inside = phantom->labels.geometry.indexToPatient({double(i), double(j), double(k)});
  REQUIRE(inside);
  char point[96];
  std::snprintf(point, sizeof point, "mm %.3f %.3f %.3f", (*inside)[0], (*inside)[1], (*inside)[2]);
  auto again = test::runApp("play quick.check --user gus --no-views --db '" + dbPath + "'",
                            "no such thing\n" + structures[1].displayName + "\n" + point + "\nquit\n");
  CHECK_MESSAGE(again.exitCode == 0, again.err);
  CHECK(again.out.find("is not a pick") != std::string::npos);
  CHECK(again.out.find("✓ Correct: that is the " + quiz::nameInSentence(structures[1].displayName)) != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == 2);
}

TEST_CASE("Interactive play: 'back' shows the step before again, an answered question with its feedback; the answer stands") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "b.db");
  storeQuickCourse(dbPath);
  const auto structures = phantomStructures();
  // Question 0 (a name question) answered; 'back' at question 1 shows question 0 with its grade
  // and moves on to question 1 again (input that is not a terminal does not wait), where 'quit' stops.
  auto r = test::runApp("play quick.check --user hal --new-user --no-views --db '" + dbPath + "'",
                        structures[0].displayName + "\nback\nquit\n");
  CHECK_MESSAGE(r.exitCode == 0, r.err);
  const auto count = [&](const std::string& text) {
    std::size_t n = 0;
    for (auto at = r.out.find(text); at != std::string::npos; at = r.out.find(text, at + 1)) ++n;
    return n;
  };
  CHECK(count("Question 0 about") == 2);
  CHECK(count("Question 1 about") == 2);
  CHECK(count("answered:") == 1);
  CHECK(count("✓ Correct") == 2);  // the grade, and the grade shown again
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == 1);
  // 'back' from an answers file too (the show step before question 0, then question 0 again).
  const fs::path file = writeLines(dir / "back.jsonl", {"back", "{\"text\": \"" + structures[0].displayName + "\"}"});
  auto fromFile = test::runApp(playArgs("quick.check", "ian", file, dbPath));
  CHECK(fromFile.out.find("Question 0 about") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses") == 2);
}

TEST_CASE("Quiz-only play skips the teaching steps and records the attempt's mode") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "q.db");
  storeQuickCourse(dbPath);
  const fs::path file = writeLines(dir / "q.jsonl", quickAnswers());
  auto r = test::runApp(playArgs("quick.check", "ida", file, dbPath) + " --quiz-only");
  CHECK_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("quiz only") != std::string::npos);
  CHECK(r.out.find("Look at it.") == std::string::npos);
  CHECK(r.out.find("\n[1/6] Question") != std::string::npos);
  CHECK(r.out.find("right (score 1.00).") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM attempts WHERE mode = 'quiz_only' AND finished_at IS NOT NULL") == 1);
}

TEST_CASE("courses and lessons list the seeded default course; seeding twice adds nothing") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "l.db");
  auto courses = test::runApp("courses --db '" + dbPath + "'");
  CHECK_MESSAGE(courses.exitCode == 0, courses.err);
  const auto lessonsBefore = scalar(dbPath, "SELECT count(*) FROM lessons");
  const auto stepsBefore = scalar(dbPath, "SELECT count(*) FROM steps");
  CHECK(lessonsBefore >= 4);
  auto lessons = test::runApp("lessons --db '" + dbPath + "'");
  CHECK_MESSAGE(lessons.exitCode == 0, lessons.err);
  CHECK(lessons.out.find("inner_ear") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM lessons") == lessonsBefore);
  CHECK(scalar(dbPath, "SELECT count(*) FROM steps") == stepsBefore);
  std::int64_t shipped = 0;  // the phantom's temporal bone and the skull
  for (const auto& e : fs::directory_iterator(test::sourceDir() / "data" / "courses")) shipped += e.path().extension() == ".json";
  CHECK(shipped == 2);
  CHECK(scalar(dbPath, "SELECT count(*) FROM courses") == shipped);
}

TEST_CASE("The TotalSegmentator sample imports with its 41 structures and carries a small abdominal course") {
  if (!appAvailable()) return;
  if (!test::requireSharedData("abdominal course")) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "abdomen.db");
  const auto ct = test::sharedData("totalsegmentator/ct_small.nii.gz");
  const auto seg = test::sharedData("totalsegmentator/seg_small.nii.gz");
  const auto names = test::sharedData("totalsegmentator/labels.json");
  const std::string importArgs = "import --volume '" + ct.string() + "' --labels '" + seg.string() + "' --names '" +
                                 names.string() + "' --name 'abdomen' --db '" + dbPath + "'";
  auto imported = test::runApp(importArgs);
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  CHECK(imported.out.find("41 structures") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM structures") == 41);
  CHECK(scalar(dbPath, "SELECT dim_x * 10000 + dim_y * 100 + dim_z FROM datasets WHERE name = 'abdomen'") ==
        122 * 10000 + 101 * 100 + 30);
  auto duplicate = test::runApp(importArgs);
  CHECK(duplicate.exitCode != 0);
  CHECK(duplicate.err.find("'abdomen' is already imported") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM datasets") == 1);
  // Labels of another scan (the head) do not align with this CT: refused, nothing registered.
  auto misaligned = test::runApp("import --volume '" + ct.string() + "' --labels '" +
                                 test::sharedData("headsq/nrrd/quarter.nhdr").string() + "' --name head_on_abdomen --db '" +
                                 dbPath + "'");
  CHECK(misaligned.exitCode != 0);
  CHECK(misaligned.err.find("overlap") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM datasets") == 1);

  // A course written here, on the imported dataset, seeded through AT_DATA_DIR.
  const std::string courseJson = R"({
    "schema": 1, "id": "abdomen_basics", "title": "Abdomen and lumbar spine", "dataset": "abdomen", "version": 1,
    "lessons": [{
      "id": "abdomen.upper", "title": "Upper abdominal organs",
      "steps": [
        {"kind": "show", "structure": "liver", "preset": "default_wdt", "view": "anterior", "title": "The liver",
         "text": "The largest solid organ, under the right dome of the diaphragm."},
        {"kind": "question", "structure": "kidney_right", "view": "anterior",
         "question": {"id": "abdomen.upper.locate_liver", "kind": "locate",
         "prompt": "Click the liver.", "target": "liver"}},
        {"kind": "question", "question": {"id": "abdomen.upper.identify_spleen", "kind": "identify",
         "prompt": "Which organ is highlighted?", "target": "spleen", "distractors": 3}},
        {"kind": "question", "question": {"id": "abdomen.upper.name_kidney", "kind": "name",
         "prompt": "Name the highlighted organ.", "target": "kidney_left"}},
        {"kind": "question", "question": {"id": "abdomen.upper.nearest_to_right_kidney", "kind": "relation",
         "prompt": "Which lies nearest to the right kidney?", "target": "kidney_right",
         "relation": {"from": "kidney_right", "kind": "nearest", "candidates": ["liver", "spleen", "lung_upper_lobe_left"]}}},
        {"kind": "question", "question": {"id": "abdomen.upper.order_back_to_aorta", "kind": "order",
         "prompt": "A needle from the left back muscles to the aorta: what does it pass, in order?", "target": "aorta",
         "order": {"entry_structure": "autochthon_left", "target_structure": "aorta"}}}
      ]}]})";
  fs::create_directories(dir / "data" / "courses");
  { std::ofstream(dir / "data" / "courses" / "abdomen.json") << courseJson; }
  auto course = lessons::parseCourseJson(courseJson, "abdomen.json");
  REQUIRE_MESSAGE(course, (course ? "" : course.error().message));

  DatasetFiles files;
  files.volumePath = ct.string();
  files.labelsPath = seg.string();
  files.namesPath = names.string();
  files.id = "abdomen";
  auto dataset = openDatasetFiles(files);
  REQUIRE(dataset);
  const auto answers = answersFor(*course, *dataset);
  const fs::path answersFile = writeLines(dir / "abdomen.jsonl", answers.at("abdomen.upper"));

  ::setenv("AT_DATA_DIR", (dir / "data").c_str(), 1);
  auto played = test::runApp(playArgs("abdomen.upper", "hal", answersFile, dbPath));
  auto progress = test::runApp("progress --user hal --db '" + dbPath + "'");
  ::unsetenv("AT_DATA_DIR");
  CHECK_MESSAGE(played.exitCode == 0, played.err);
  CHECK(played.out.find("right (score 1.00).") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses WHERE correct = 1") == 5);
  CHECK_MESSAGE(progress.exitCode == 0, progress.err);
  CHECK(progress.out.find("Kidney right") != std::string::npos);
}

TEST_CASE("play --review asks only about taught structures that are due, and progress counts the same") {
  if (!appAvailable()) return;
  test::TempDir dir;
  const std::string dbPath = test::freshDatabase(dir, "rv.db");
  storeQuickCourse(dbPath);
  const auto structures = phantomStructures();
  const auto answers = quickAnswers();
  const auto run = [&](const std::string& user, const std::vector<std::string>& lines, const std::string& name) {
    const fs::path file = writeLines(dir / name, lines);
    return test::runApp("play --review quick --user " + user + " --new-user --no-views --answers '" + file.string() +
                        "' --db '" + dbPath + "'");
  };
  // Time passes for one user: every due time and last answer moves `days` into the past.
  const auto daysPass = [&](const std::string& user, int days) {
    auto db = db::Database::open(dbPath);
    REQUIRE(db);
    auto shift = db->prepare("UPDATE memory_states SET due_at = due_at - ?1, last_review_at = last_review_at - ?1"
                             " WHERE user_id = (SELECT id FROM users WHERE name = ?2)");
    REQUIRE(shift);
    shift->bind(1, std::int64_t(days) * 86400).bind(2, user);
    REQUIRE(shift->run());
    // Equal Elo ratings for everyone, so the adaptive choice goes by question id (q0, q1, …).
    REQUIRE(db->exec("DELETE FROM question_stats; DELETE FROM user_ability;"));
  };

  // Nothing taught yet: nothing is asked, and the student is told to start with a lesson.
  auto fresh = run("hal", {answers[0]}, "unused.jsonl");
  CHECK_MESSAGE(fresh.exitCode == 0, fresh.err);
  CHECK(fresh.out.find("Review asks about what you have been taught") != std::string::npos);
  CHECK(fresh.out.find("Nothing is due for review") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM review_responses") == 0);

  // The lesson teaches four structures; right after it nothing is due (learning steps of minutes,
  // days for those answered twice).
  const fs::path lessonFile = writeLines(dir / "lesson.jsonl", answers);
  auto lesson = test::runApp(playArgs("quick.check", "hal", lessonFile, dbPath));
  REQUIRE_MESSAGE(lesson.exitCode == 0, lesson.err);
  CHECK(scalar(dbPath, "SELECT count(*) FROM memory_states") == 4);
  CHECK(scalar(dbPath, "SELECT count(*) FROM review_log WHERE source = 'lesson' AND rating = 3") == 6);  // untimed: Good
  auto early = run("hal", {answers[0]}, "early.jsonl");
  CHECK(early.out.find("Nothing is due for review") != std::string::npos);
  auto none = test::runApp("progress --user hal --db '" + dbPath + "'");
  CHECK(none.out.find("Due for review now: nothing") != std::string::npos);

  // Forty days later all four are due: `progress` and `play --review` agree on them.
  daysPass("hal", 40);
  auto due = test::runApp("progress --user hal --db '" + dbPath + "'");
  CHECK_MESSAGE(due.exitCode == 0, due.err);
  CHECK(due.out.find("quick: 4 structures (") != std::string::npos);
  auto r = run("hal", {answers[0], answers[1], answers[2], answers[3]}, "review.jsonl");
  CHECK_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("Due now: 4 structures") != std::string::npos);
  CHECK(r.out.find("[review 1] Question (name)") != std::string::npos);
  CHECK(r.out.find("[review 2] Question (locate)") != std::string::npos);
  CHECK(r.out.find("[review 4] Question (name)") != std::string::npos);
  CHECK(r.out.find("Nothing more is due for review") != std::string::npos);
  CHECK(r.out.find("Review answers saved: 4, 4 correct.") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM review_responses WHERE correct = 1 AND mode = 'terminal'") == 4);
  CHECK(scalar(dbPath, "SELECT count(*) FROM review_log WHERE source = 'review'") == 4);
  auto after = test::runApp("progress --user hal --db '" + dbPath + "'");
  CHECK(after.out.find("10 answers, 10 correct (4 in review, 4 correct)") != std::string::npos);
  CHECK(after.out.find("Due for review now: nothing") != std::string::npos);

  // Another student forgets: the first structure (answered twice in the lesson: in Review) named
  // wrongly is a lapse, Relearning for 10 minutes; the answers then end, which ends the review.
  const fs::path ivyLesson = writeLines(dir / "ivy.jsonl", answers);
  REQUIRE(test::runApp(playArgs("quick.check", "ivy", ivyLesson, dbPath)).exitCode == 0);
  daysPass("ivy", 40);
  quiz::Answer wrong;
  wrong.text = structures[1].displayName;
  auto w = run("ivy", {quiz::answerToJson(wrong)}, "wrong.jsonl");
  CHECK_MESSAGE(w.exitCode == 0, w.err);
  CHECK(w.out.find("✗ Not quite") != std::string::npos);
  CHECK(w.out.find("Review answers saved: 1, 0 correct.") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT m.due_at - m.last_review_at FROM memory_states m JOIN users ON users.id = m.user_id"
                       " WHERE users.name = 'ivy' AND m.structure = '" + structures[0].id + "' AND m.phase = 'relearning'") == 600);

  // A malformed line names its line and records nothing; a lesson and --review together are refused.
  auto b = run("ivy", {"{\"text\": "}, "broken.jsonl");
  CHECK(b.exitCode != 0);
  CHECK(b.err.find("broken.jsonl:1: ") != std::string::npos);
  CHECK(scalar(dbPath, "SELECT count(*) FROM review_responses") == 5);
  auto both = test::runApp("play quick.check --review quick --user hal --db '" + dbPath + "'");
  CHECK(both.exitCode != 0);
  CHECK(both.err.find("not both") != std::string::npos);
  auto unknown = test::runApp("play --review nope --user hal --db '" + dbPath + "'");
  CHECK(unknown.exitCode != 0);
  CHECK(unknown.err.find("unknown course 'nope'") != std::string::npos);
}

TEST_CASE("The skull course travels as a package to a program without it and plays to 1.00 from the package") {
  if (!appAvailable()) return;
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::SkullCacheScope scope(*cache);
  test::TempDir dir;
  const fs::path courseFile = test::sourceDir() / "data" / "courses" / "skull.json";
  auto valid = test::runApp("course validate '" + courseFile.string() + "'");
  REQUIRE_MESSAGE(valid.exitCode == 0, valid.err);
  CHECK(valid.out.find("structures checked against dataset 'skull'") != std::string::npos);
  const fs::path package = dir / "skull.atcourse";
  auto exported = test::runApp("course export skull --out '" + package.string() + "' --db '" + (dir / "author.db").string() + "'");
  REQUIRE_MESSAGE(exported.exitCode == 0, exported.err);

  // The student's program ships only the phantom's course; the skull CT and its labels are set-up's.
  fs::create_directories(dir / "data" / "courses");
  fs::copy_file(test::sourceDir() / "data" / "courses" / "temporal_bone.json", dir / "data" / "courses" / "temporal_bone.json");
  test::ScopedEnvVar data("AT_DATA_DIR", (dir / "data").string());
  const std::string dbPath = test::freshDatabase(dir, "student.db");
  auto before = test::runApp("courses --db '" + dbPath + "'");
  REQUIRE_MESSAGE(before.exitCode == 0, before.err);
  CHECK(before.out.find("The skull on CT") == std::string::npos);
  auto imported = test::runApp("course import '" + package.string() + "' --db '" + dbPath + "'");
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  auto course = lessons::loadCourseJson(courseFile);
  REQUIRE_MESSAGE(course, test::errorText(course));
  CHECK(imported.out.find("course 'skull' (The skull on CT) version " + std::to_string(course->version) + ": added") !=
        std::string::npos);
  CHECK(imported.out.find("dataset 'skull': built in") != std::string::npos);

  auto dataset = openKnownScan(*findKnownScan("skull"));
  REQUIRE_MESSAGE(dataset, test::errorText(dataset));
  int questions = 0;
  playEveryLesson(*course, *dataset, dir, "ana", dbPath, questions);
  CHECK(questions == 14);
  CHECK(scalar(dbPath, "SELECT count(*) FROM responses WHERE correct = 0") == 0);
}

TEST_CASE("A class through the CLI: join with the code, play while the server is down, sync, the instructor's view") {
  if (!appAvailable()) return;
  test::PrivatePostgres classServer;  // stopped below: a cluster of its own, not the shared one
  auto url = classServer.freshDatabase("the class-server CLI test");
  if (!url) return;
  test::TempDir dir;
  const std::string server = " --db '" + *url + "'", local = (dir.path() / "laptop.db").string();
  storeQuickCourse(local);
  storeQuickCourse(*url);  // the server judges events against the course
  const fs::path answers = writeLines(dir.path() / "answers.jsonl", quickAnswers());

  auto made = test::runApp("class create 'Ear anatomy' --user dr_ada" + server);
  CAPTURE(made.err);
  REQUIRE(made.exitCode == 0);
  const auto codeAt = made.out.find("code ");
  REQUIRE(codeAt != std::string::npos);
  const std::string code = made.out.substr(codeAt + 5, 8);
  CHECK(made.out.find("make each person's login with: anatomy-tutor class account " + code) != std::string::npos);
  CHECK(made.out.find(":" + std::string("@")) == std::string::npos);
  // The coordinator publishes the course's answer keys from a machine that has the course: the
  // server grades every answer with them.
  auto keys = test::runApp("class keys " + code + " --course quick --user dr_ada --local-db '" + local + "'" + server);
  CAPTURE(keys.err);
  REQUIRE(keys.exitCode == 0);
  CHECK(keys.out.find("course quick: 6 keys published to class " + code) != std::string::npos);

  for (const char* name : {"sam", "kim"}) {
    auto joined = test::runApp("class join " + code + " --server '" + *url + "' --user " + name + " --db '" + local + "'");
    CAPTURE(joined.err);
    CHECK(joined.exitCode == 0);
    CHECK(joined.out.find(std::string(name) + " joined class " + code + " (Ear anatomy) as student") != std::string::npos);
  }
  // Online: play sends each answer as it goes.
  auto online = test::runApp(playArgs("quick.check", "sam", answers, local));
  CAPTURE(online.err);
  REQUIRE(online.exitCode == 0);
  CHECK(scalar(local, "SELECT COUNT(*) FROM outbox WHERE sent_at IS NULL") == 0);
  CHECK(scalar(local, "SELECT COUNT(*) FROM outbox") == 8);  // start, 6 answers, finish

  // Offline: the lesson goes on, the answers wait, sync says why and fails; back: they go, once.
  REQUIRE(classServer.stop());
  auto offline = test::runApp(playArgs("quick.check", "kim", answers, local));
  auto syncDown = test::runApp("sync --db '" + local + "'");
  const bool restarted = classServer.restart();
  REQUIRE(restarted);
  CAPTURE(offline.err);
  CHECK(offline.exitCode == 0);
  CHECK(offline.out.find("Lesson finished: 6 of 6 questions right") != std::string::npos);
  CHECK(offline.out.find("wait in the outbox") != std::string::npos);
  CHECK(syncDown.exitCode == 1);
  CHECK(syncDown.err.find("8 events wait in the outbox (cannot reach the database server") != std::string::npos);
  CHECK(std::count(syncDown.err.begin(), syncDown.err.end(), '\n') == 1);
  auto syncUp = test::runApp("sync --db '" + local + "'");
  CAPTURE(syncUp.err);
  CHECK(syncUp.exitCode == 0);
  CHECK(syncUp.out.find("8 events sent") != std::string::npos);
  auto again = test::runApp("sync --db '" + local + "'");
  CHECK(again.exitCode == 0);
  CHECK(again.out.find("nothing to send") != std::string::npos);

  auto csv = test::runApp("class progress " + code + " --user dr_ada --csv" + server);
  CAPTURE(csv.err);
  REQUIRE(csv.exitCode == 0);
  // Their locate answers are named picks ({"pick": …}), not pixels on the question's picture: the
  // server keeps them as practice (the last column), apart from the answers it graded.
  int locate = 0;
  for (const auto& step : quickCourse().lessons[0].steps)
    locate += step.kind == lessons::StepKind::Question && step.question.kind == quiz::QuestionKind::Locate;
  CHECK(locate > 0);
  for (const char* name : {"kim", "sam"}) {
    CAPTURE(name);
    const std::string graded = std::to_string(6 - locate);
    const auto at = csv.out.find("\n" + std::string(name) + ",");
    REQUIRE(at != std::string::npos);
    const std::string rest = csv.out.substr(at + 2 + std::strlen(name));
    const std::string line = rest.substr(0, rest.find('\n'));
    CHECK(line.rfind(graded + "," + graded + ",", 0) == 0);
    CHECK(line.find(",1,1,") != std::string::npos);
    CHECK(line.ends_with(",0," + std::to_string(locate)));
  }
  auto table = test::runApp("class progress " + code + " --user dr_ada" + server);
  CHECK(table.out.find("2 students, 16 events received") != std::string::npos);

  // The same records as xAPI statements: sam's attempt (attempted, completed) and six answers.
  auto xapi = test::runApp("xapi --user sam --out '" + (dir.path() / "sam.json").string() + "' --db '" + local + "'");
  CAPTURE(xapi.err);
  REQUIRE(xapi.exitCode == 0);
  CHECK(xapi.out.find("statements of 1 user, 7 attempts and answers") != std::string::npos);
  const auto statements = nlohmann::json::parse(test::readFile(dir.path() / "sam.json"));
  REQUIRE(statements.size() == 8);
  int answered = 0;
  for (const auto& st : statements) answered += st.at("verb").at("display").at("en-US") == "answered";
  CHECK(answered == 6);
  // As a record store would take them: through Learning Locker's validator, where Node.js is here.
  if (std::system("command -v node > /dev/null 2>&1") == 0) {
    const std::string validate = "bash '" + (test::sourceDir() / "scripts/xapi-validator.sh").string() +
                                 "' validate '" + (dir.path() / "sam.json").string() + "' > /dev/null 2>&1";
    CHECK(std::system(validate.c_str()) == 0);
  } else {
    at::test::skipf("validating the CLI's xAPI statements needs Node.js (scripts/install-deps.sh)");
  }

  // Refusals: one line naming what is wrong.
  auto student = test::runApp("class progress " + code + " --user sam" + server);
  CHECK(student.exitCode == 1);
  CHECK(student.err.find("'sam' is a student of class " + code) != std::string::npos);
  auto badCode = test::runApp("class join K7M2-P9Q --server '" + *url + "' --user ann --db '" + local + "'");
  CHECK(badCode.exitCode == 1);
  CHECK(badCode.err.find("class code 'K7M2-P9Q'") != std::string::npos);
  auto unknown = test::runApp("class join ZZZZZZZZ --server '" + *url + "' --user ann --db '" + local + "'");
  CHECK(unknown.exitCode == 1);
  CHECK(unknown.err.find("no class has the code ZZZZZZZZ") != std::string::npos);
  auto notServer = test::runApp("class join " + code + " --server '" + local + "' --user ann");
  CHECK(notServer.exitCode == 1);
  CHECK(notServer.err.find("is not a class server") != std::string::npos);
  auto role = test::runApp("class role " + code + " kim instructor --user sam" + server);
  CHECK(role.exitCode == 1);
  CHECK(role.err.find("only its coordinators give roles") != std::string::npos);
  CHECK(test::runApp("class role " + code + " kim instructor --user dr_ada" + server).exitCode == 0);
  CHECK(test::runApp("class progress " + code + " --user kim" + server).exitCode == 0);
}
