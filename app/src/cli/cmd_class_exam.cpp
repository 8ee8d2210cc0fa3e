// Graded exams on a class server from the terminal (db/class_exams.h):
//   class open-exam CODE EXAM   an instructor draws the exam's items on their machine (which has the
//                               course and its dataset), renders every item's view as a picture,
//                               works out which pixels of a locate item's picture count (the laptop's
//                               grader, pixel by pixel), and hands items and keys to the server;
//   class close-exam CODE EXAM  ends it (open sittings are handed in);
//   exam EXAM --user NAME       on a machine whose user joined a class that has EXAM open: the items
//                               come from the server as pictures, each answer (a locate item's: the
//                               pixel clicked) is sent there and graded there.
#include "class_exam_cli.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iterator>
#include <map>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "core/atomic_file.h"
#include "core/strings.h"
#include "db/class_accounts.h"
#include "db/class_exams.h"
#include "db/class_server.h"
#include "learning_session.h"
#include "lessons/exam.h"
#include "lessons/lesson_engine.h"
#include "printable_output.h"
#include "terminal_answers.h"
#include "terminal_locate_key.h"
#include "terminal_views.h"

namespace at::app {

namespace {

constexpr std::string_view kBase64 = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

std::string toBase64(const std::string& bytes) {
  std::string out;
  std::uint32_t bits = 0;
  int count = 0;
  for (unsigned char c : bytes) {
    bits = (bits << 8) | c;
    count += 8;
    while (count >= 6) out += kBase64[(bits >> (count -= 6)) & 63];
  }
  if (count > 0) out += kBase64[(bits << (6 - count)) & 63];
  while (out.size() % 4) out += '=';
  return out;
}

std::string fromBase64(const std::string& text) {
  std::string out;
  std::uint32_t bits = 0;
  int count = 0;
  for (char c : text) {
    const auto at = kBase64.find(c);
    if (at == std::string_view::npos) continue;  // '=' and line breaks
    bits = (bits << 6) | std::uint32_t(at);
    count += 6;
    if (count >= 8) out += char((bits >> (count -= 8)) & 0xff);
  }
  return out;
}

Result<std::string> readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail(path + ": cannot be read");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string clock(std::int64_t seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%lld:%02lld", (long long)(seconds / 60), (long long)(seconds % 60));
  return text;
}

}  // namespace

int runClassOpenExam(const cli::Args& args) {
  if (args.positional().size() != 3) return reportError("class open-exam: give CODE EXAM");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class open-exam: " + code.error().message);
  const std::string examId = args.positional()[2];
  if (!args.db() || !db::isPostgresUrl(*args.db()))
    return reportError("class open-exam: --db SERVER (the class server's postgresql:// URL) is required");
  // The items are drawn from the course on this machine (--local-db, default the usual one).
  auto learning = LearningSession::open(args.value("local-db"));
  if (!learning) return reportError("class open-exam: " + learning.error().message);
  LearningSession& ls = **learning;
  auto found = lessons::findExam(ls.curriculum(), examId);
  if (!found) return reportError("class open-exam: " + found.error().message + " (see `anatomy-tutor lessons`)");
  const lessons::Course& course = found->first;
  const lessons::ExamSpec& spec = found->second;
  auto structures = ls.structures(course.datasetId);
  if (!structures) return reportError("class open-exam: " + structures.error().message);
  auto keys = ls.keysFor(course.datasetId);
  if (!keys) return reportError("class open-exam: " + keys.error().message);
  auto items = lessons::drawExamItems(spec, *structures, **keys, "class|" + *code + "|" + examId, &course);
  if (!items) return reportError("class open-exam: " + items.error().message);
  const quiz::GradingContext context = lessons::gradingContext(*structures, course);

  // Every item goes to the server as a picture: an identify or name item's scene would name the
  // answer; a locate item is clicked on its picture and graded there from the pixel.
  const std::string dir = args.valueOr("views", "anatomy-tutor-views");
  auto made = TerminalViews::create(ls.database(), course.datasetId, dir, true);
  if (!made) return reportError("class open-exam: the items' pictures cannot be made: " + made.error().message);
  std::unique_ptr<TerminalViews> views = std::move(*made);
  db::ClassExamOpening opening;
  opening.examId = examId;
  opening.courseId = course.id;
  opening.title = spec.title;
  opening.timeLimitS = spec.timeLimitS;
  opening.passScore = spec.passScore;
  opening.prerequisites = spec.prerequisites;
  for (const lessons::ExamItem& item : *items) {
    const quiz::ResolvedQuestion& q = item.question;
    db::ClassExamItem shown;
    db::ClassExamKey key;
    shown.position = item.position;
    shown.prompt = q.question.prompt;
    key.questionId = q.question.id;
    key.target = q.question.target;
    char stem[200];
    std::snprintf(stem, sizeof stem, "%s-%s-item%02d", code->c_str(), examId.c_str(), item.position + 1);
    const bool locate = q.question.kind == quiz::QuestionKind::Locate;
    // A locate item's picture is the view the student's machine showed before: the target's
    // region, from a side where it can be clicked (or its axial slice).
    auto picture = !locate ? views->show(item.scene, stem)
                   : item.locateView == lessons::ExamLocateView::Slice ? views->showSlice(q.question.target, stem)
                                                                       : views->show(item.scene, stem, true, q.question.target);
    if (!picture)
      return reportError("class open-exam: item " + std::to_string(item.position + 1) + ": " + picture.error().message);
    auto bytes = readBytes(picture->path);
    if (!bytes) return reportError("class open-exam: " + bytes.error().message);
    shown.pictureBase64 = toBase64(*bytes);
    std::error_code ignored;
    std::filesystem::remove(picture->path, ignored);  // it shows the answer: not left lying about
    if (locate) {
      shown.kind = "locate";
      shown.locateView = lessons::toString(item.locateView);
      shown.sceneJson = nlohmann::json{{"structure", item.scene.structure}, {"preset", item.scene.presetId},
                                       {"view", lessons::toString(item.scene.view)}, {"target", q.question.target}}
                            .dump();
      shown.pictureWidth = picture->width;
      shown.pictureHeight = picture->height;
      key.toleranceMm = q.question.toleranceMm;
      auto runs = acceptedPixelRuns(*views, *picture, q, context);
      if (!runs) return reportError("class open-exam: item " + std::to_string(item.position + 1) + ": " + runs.error().message);
      key.acceptedPixels = std::move(*runs);
    } else {
      shown.kind = q.question.kind == quiz::QuestionKind::Identify ? "identify" : "name";
      shown.choices = q.choices;
      key.keyChoice = q.keyChoice;
      if (q.question.kind == quiz::QuestionKind::Name) db::setNameKey(key, q, context);
    }
    opening.items.push_back(std::move(shown));
    opening.keys.push_back(std::move(key));
  }
  db::OpenOptions options;
  options.create = false;
  auto server = db::openDatabase(*args.db(), options);
  if (!server) return reportError("class open-exam: " + server.error().message);
  auto opened = db::openClassExam(*server, *code, opening, args.user());
  if (!opened) return reportError("class open-exam: " + opened.error().message);
  terminalPrintf("exam %s (%s) is open in class %s: %s, %s each sitting; its keys stay on the server\n",
                 examId.c_str(), spec.title.c_str(), code->c_str(), str::countOf(*opened, "item").c_str(),
                 clock(spec.timeLimitS).c_str());
  return 0;
}

int runClassCloseExam(const cli::Args& args) {
  if (args.positional().size() != 3) return reportError("class close-exam: give CODE EXAM");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class close-exam: " + code.error().message);
  if (!args.db() || !db::isPostgresUrl(*args.db()))
    return reportError("class close-exam: --db SERVER (the class server's postgresql:// URL) is required");
  db::OpenOptions options;
  options.create = false;
  auto server = db::openDatabase(*args.db(), options);
  if (!server) return reportError("class close-exam: " + server.error().message);
  auto closed = db::closeClassExam(*server, *code, args.positional()[2], args.user());
  if (!closed) return reportError("class close-exam: " + closed.error().message);
  terminalPrintf("exam %s of class %s is closed (%s handed in now)\n", args.positional()[2].c_str(), code->c_str(),
                 str::countOf(*closed, "open sitting").c_str());
  return 0;
}

std::optional<int> runServerExam(LearningSession& ls, const std::string& userName, const std::string& examId,
                                 AnswerSource& source, const std::optional<std::string>& viewsDir, bool noViews) {
  auto membership = db::membershipOf(ls.database(), userName);
  if (!membership || !*membership) return std::nullopt;  // not in a class: the exam is this machine's
  const db::ClassMembership& m = **membership;
  db::ServerConnections connections;  // waits 3 s at most for a server that is away
  auto reached = connections.get(m.server, 3);
  if (!reached) {
    terminalPrintf("  (class %s's server cannot be reached: %s)\n", m.classCode.c_str(), reached.error().message.c_str());
    return std::nullopt;
  }
  db::Database* server = *reached;
  auto open = db::classExamOpen(*server, m.classCode, examId);
  if (!open || !*open) return std::nullopt;

  auto sitting = db::startClassExam(*server, m.classCode, examId, userName);
  if (!sitting) return reportError("exam: " + sitting.error().message);
  const auto localStart = std::chrono::steady_clock::now();
  const auto secondsLeft = [&] {
    const auto elapsed = std::chrono::duration_cast<std::chrono::seconds>(std::chrono::steady_clock::now() - localStart);
    return std::max<std::int64_t>(0, sitting->deadline - sitting->serverNow - elapsed.count());
  };
  terminalPrintf("Graded exam of class %s: %s (%s), %s, %s left. Graded on the class server; no answer is marked "
                 "until you hand in.\n",
                 m.classCode.c_str(), sitting->title.c_str(), examId.c_str(),
                 str::countOf(long(sitting->items.size()), "item").c_str(), clock(secondsLeft()).c_str());

  // The choices are listed by name from this machine's copy of the course, when it has it.
  std::map<std::string, std::string> idByName, nameById;
  if (auto found = lessons::findExam(ls.curriculum(), examId))
    if (auto structures = ls.structures(found->first.datasetId)) {
      idByName = structureIdsByName(*structures);
      for (const Structure& s : *structures) nameById[s.id] = s.displayName.empty() ? s.id : s.displayName;
    }
  const std::filesystem::path dir = viewsDir.value_or("anatomy-tutor-views");
  bool handIn = sitting->handedIn;
  if (handIn) terminalPrintf("You handed this exam in already; nothing more is graded.\n");
  for (int round = 0; round < 2 && !handIn && secondsLeft() > 0; ++round) {
    for (const db::ClassExamItem& item : sitting->items) {
      if (sitting->answered.count(item.position) || handIn || secondsLeft() <= 0) continue;
      terminalPrintf("\n[%d/%zu] %s left — %s\n", item.position + 1, sitting->items.size(), clock(secondsLeft()).c_str(),
                     item.prompt.c_str());
      for (std::size_t i = 0; i < item.choices.size(); ++i)
        terminalPrintf("    %zu) %s\n", i, (nameById.count(item.choices[i]) ? nameById[item.choices[i]] : item.choices[i]).c_str());
      AskedQuestion q;
      q.kind = item.kind == "locate" ? quiz::QuestionKind::Locate
               : item.kind == "identify" ? quiz::QuestionKind::Identify : quiz::QuestionKind::Name;
      q.choiceIds = item.choices;
      q.idByName = idByName;
      char stem[200];
      std::snprintf(stem, sizeof stem, "%s-%02d", examId.c_str(), item.position + 1);
      // Every item comes as a picture; a locate item is answered with the pixel clicked on it.
      if (q.kind == quiz::QuestionKind::Locate) q.serverPictureSize = std::array<int, 2>{item.pictureWidth, item.pictureHeight};
      if (!item.pictureBase64.empty() && (!noViews || q.kind == quiz::QuestionKind::Locate)) {
        std::error_code ignored;
        std::filesystem::create_directories(dir, ignored);
        const std::string path = (dir / (std::string(stem) + ".png")).string();
        if (auto written = writeFileAtomically(path, fromBase64(item.pictureBase64)); written)
          terminalPrintf("  view: %s%s\n", path.c_str(),
                         q.kind == quiz::QuestionKind::Locate ? "  — answer with the pixel x y where it is" : "");
      }
      std::fflush(stdout);
      auto asked = askQuestion(source, q, [&](const quiz::Answer& a, std::int64_t latencyMs) -> Result<std::optional<quiz::Grade>> {
        db::ClassExamAnswer sent;
        sent.choice = a.choice;
        sent.text = a.text;
        if (a.pick) sent.pixel = a.pick->pixel;
        sent.latencyMs = latencyMs;
        if (auto st = db::answerClassExam(*server, m.classCode, examId, item.position, sent, userName); !st)
          return tl::unexpected(st.error());
        terminalPrintf("  (sent)\n");
        return std::optional<quiz::Grade>();
      }, true);
      if (!asked) return reportError("exam: " + asked.error().message + " (earlier answers are on the server)");
      if (*asked == Asked::Answered) sitting->answered.insert(item.position);
      if (*asked == Asked::Quit || (*asked == Asked::InputEnded && source.interactive())) {
        terminalPrintf("\nleft the exam with %s to go; your answers are on the server and the clock runs on — run the "
                       "same command to continue\n", clock(secondsLeft()).c_str());
        return 0;
      }
      if (*asked == Asked::Finish || *asked == Asked::InputEnded) handIn = true;
    }
    if (!source.interactive()) break;
  }
  auto result = db::finishClassExam(*server, m.classCode, examId, userName);
  if (!result) return reportError("exam: " + result.error().message);
  int right = 0;
  for (const auto& x : result->items) right += x.correct ? 1 : 0;
  terminalPrintf("\n%s Results from the class server: %d of %s right, score %.2f", sitting->handedIn ? "Handed in earlier." : "Handed in.", right,
                 str::countOf(long(result->items.size()), "item").c_str(), result->score);
  if (result->passed) terminalPrintf(" — %s", *result->passed ? "passed" : "not passed");
  terminalPrintf("\n");
  for (const auto& x : result->items)
    terminalPrintf("  %2d. %s\n", x.position + 1, !x.answered ? "– not answered" : x.correct ? "✓ right" : "✗ wrong");
  return 0;
}

Result<std::vector<lessons::LearnerRecords>> classExamLearners(db::Database& server, const std::string& code) {
  auto sittings = db::classExamSittings(server, code);
  if (!sittings) return tl::unexpected(sittings.error());
  auto answers = db::classExamAnswers(server, code);
  if (!answers) return tl::unexpected(answers.error());
  std::vector<lessons::LearnerRecords> out;
  for (const db::ClassExamSittingRow& s : *sittings) {
    if (out.empty() || out.back().user.name != s.userName) {
      out.emplace_back();
      out.back().user.name = s.userName;
    }
    lessons::ExamRecord record;
    record.attempt.examId = s.examId;
    record.attempt.courseId = s.courseId;
    record.attempt.startedAt = s.startedAt;
    record.attempt.finishedAt = s.finishedAt;
    record.attempt.score = s.score.value_or(0);
    record.attempt.passed = s.passed;
    for (const db::ClassExamAnswerRow& a : *answers) {
      if (a.userName != s.userName || a.examId != s.examId) continue;
      lessons::ExamItem item;
      item.position = a.position;
      item.question.question.id = s.examId + "." + code + ".item" + std::to_string(a.position + 1);  // per class: its own draw
      item.question.question.kind = a.kind == "locate"     ? quiz::QuestionKind::Locate
                                    : a.kind == "identify" ? quiz::QuestionKind::Identify
                                                           : quiz::QuestionKind::Name;
      item.question.choices = a.choices;
      const auto given = nlohmann::json::parse(a.answerJson, nullptr, false);
      quiz::Answer answer;
      if (given.is_object()) {
        if (given.contains("choice") && given["choice"].is_number_integer()) answer.choice = given["choice"].get<int>();
        if (given.contains("text") && given["text"].is_string()) answer.text = given["text"].get<std::string>();
        if (given.contains("pick") && given["pick"].is_object()) {  // graded before the server took pixels
          quiz::Pick pick;
          const auto& p = given["pick"];
          if (p.contains("structure") && p["structure"].is_string()) pick.structure = p["structure"].get<std::string>();
          if (p.contains("distance_mm") && p["distance_mm"].is_number()) pick.distanceMm = p["distance_mm"].get<double>();
          answer.pick = pick;
        }
        if (given.contains("pixel") && given["pixel"].is_array() && given["pixel"].size() == 2 &&
            given["pixel"][0].is_number_integer() && given["pixel"][1].is_number_integer()) {
          answer.pick = quiz::Pick{};
          answer.pick->pixel = std::array<int, 2>{given["pixel"][0].get<int>(), given["pixel"][1].get<int>()};
        }
      }
      item.answer = answer;
      item.correct = a.correct;
      item.score = a.score;
      item.latencyMs = a.latencyMs;
      item.answeredAt = a.answeredAt;
      record.items.push_back(std::move(item));
    }
    out.back().exams.push_back(std::move(record));
  }
  return out;
}

}  // namespace at::app
