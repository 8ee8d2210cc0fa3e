// anatomy-tutor xapi: learning records (and a study's ratings) as xAPI statements for a learning
// record store or an LMS (lessons/xapi.h).
#include <cstdio>
#include <fstream>
#include <set>

#include "class_exam_cli.h"
#include "cli_args.h"
#include "commands.h"
#include "core/atomic_file.h"
#include "core/strings.h"
#include "db/class_server.h"
#include "db/exam_store.h"
#include "db/study_store.h"
#include "learning_session.h"
#include "lessons/xapi.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kXapiHelp =
    "usage: anatomy-tutor xapi --out FILE.json [--user NAME] [--homepage URL] [--activity-base URL] [--db PATH]\n"
    "       anatomy-tutor xapi --out FILE.json --study STUDY [--homepage URL] [--activity-base URL] [--db PATH]\n"
    "       anatomy-tutor xapi --out FILE.json --class CODE --db SERVER [--homepage URL] [--activity-base URL]\n\n"
    "Writes learning records as xAPI 1.0.3 statements (a JSON array, as a learning record store\n"
    "takes them on POST /statements): every lesson attempt (attempted; completed with its score),\n"
    "every answer to a lesson or review question (answered, on a cmi.interaction: locate 'other',\n"
    "identify 'choice', name 'fill-in', order 'sequencing', with success, score and time taken;\n"
    "choice and sequencing with the choices offered and the correct response), every exam attempt\n"
    "(attempted; each answered item; completed with its score and pass) — of NAME, or of every\n"
    "user. With --study, the study's ratings instead: each an answered\n"
    "statement on a 'likert' interaction with the study's scale, the participant's pseudonym as\n"
    "actor and their enrolment as registration. Exporting the same records again gives the same\n"
    "statement ids, so a record store keeps each once.\n"
    "With --class (an instructor's or coordinator's login on the class server): the class's graded\n"
    "exams, each sitting attempted, each graded answer, completed with the server's score and pass.\n"
    "  --homepage       the system the pseudonyms are accounts of (default http://localhost/anatomy-tutor)\n"
    "  --activity-base  prefix of activity ids (default <homepage>/xapi)\n";

Result<lessons::LearnerRecords> recordsOf(LearningSession& session, const lessons::User& user) {
  lessons::LearnerRecords r;
  r.user = user;
  auto attempts = session.progress().attempts(user.id);
  if (!attempts) return tl::unexpected(attempts.error());
  r.attempts.assign(attempts->rbegin(), attempts->rend());  // oldest first
  for (const lessons::Attempt& a : r.attempts) {
    auto responses = session.progress().responses(a.id);
    if (!responses) return tl::unexpected(responses.error());
    r.responses[a.id] = std::move(*responses);
  }
  auto reviews = session.progress().reviewResponses(user.id);
  if (!reviews) return tl::unexpected(reviews.error());
  r.reviews = std::move(*reviews);
  db::SqlExamRepository exams(session.database());
  auto examAttempts = exams.examAttempts(user.id);
  if (!examAttempts) return tl::unexpected(examAttempts.error());
  for (const lessons::ExamAttempt& a : *examAttempts) {
    auto items = exams.examItems(a.id);
    if (!items) return tl::unexpected(items.error());
    r.exams.push_back({a, std::move(*items)});
  }
  return r;
}

// The choice and order questions `learners` answered in lessons and reviews, resolved on their
// courses' datasets as they were asked (choices in the order shown, keys), with the structures'
// names. A question whose course or dataset is not here is left out (exported as "other").
lessons::XapiQuestions answeredQuestions(LearningSession& session, const std::vector<lessons::LearnerRecords>& learners) {
  std::set<std::string> wanted;
  const auto want = [&](const lessons::GradedAnswer& g) {
    if (g.answer.choice || g.answer.order) wanted.insert(g.questionId);
  };
  for (const auto& r : learners) {
    for (const auto& [attempt, responses] : r.responses)
      for (const auto& x : responses) want(x);
    for (const auto& x : r.reviews) want(x);
  }
  lessons::XapiQuestions out;
  if (wanted.empty()) return out;
  auto courses = session.curriculum().courses();
  if (!courses) return out;
  for (const lessons::Course& course : *courses) {
    std::map<std::string, std::string> names;
    if (auto structures = session.structures(course.datasetId))
      for (const Structure& s : *structures) names[s.id] = s.displayName;
    for (const lessons::Lesson& lesson : course.lessons)
      for (const lessons::Step& step : lesson.steps) {
        if (step.kind != lessons::StepKind::Question || !wanted.count(step.question.id) || out.count(step.question.id))
          continue;
        auto keys = session.keysFor(course.datasetId);
        if (!keys) continue;
        auto resolved = quiz::resolveQuestion(step.question, **keys);
        if (resolved) out[step.question.id] = {std::move(*resolved), names};
      }
  }
  return out;
}

}  // namespace

int runXapi(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"out", "study", "homepage", "activity-base", "class"}, {});
  if (!args) return reportError("xapi: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kXapiHelp);
    return 0;
  }
  if (!args->positional().empty()) return reportError("xapi: unexpected argument '" + args->positional()[0] + "'");
  const auto out = args->value("out");
  if (!out) return reportError("xapi: --out FILE.json is required");
  if (args->value("study") && args->user()) return reportError("xapi: give --study STUDY or --user NAME, not both");
  lessons::XapiOptions options;
  options.homePage = args->valueOr("homepage", options.homePage);
  options.activityBase = args->valueOr("activity-base", options.homePage + "/xapi");
  options.appVersion = AT_VERSION;
  if (auto ok = lessons::checkXapiOptions(options); !ok) return reportError("xapi: " + ok.error().message);

  if (const auto classCode = args->value("class")) {
    if (args->value("study") || args->user()) return reportError("xapi: --class CODE goes alone (no --study or --user)");
    if (!args->db() || !db::isPostgresUrl(*args->db()))
      return reportError("xapi: --class CODE needs --db SERVER (the class server's postgresql:// URL)");
    auto code = db::normalizeClassCode(*classCode);
    if (!code) return reportError("xapi: " + code.error().message);
    db::OpenOptions open;
    open.create = false;
    auto server = db::openDatabase(*args->db(), open);
    if (!server) return reportError("xapi: " + server.error().message);
    auto learners = classExamLearners(*server, *code);
    if (!learners) return reportError("xapi: " + learners.error().message);
    std::size_t sittings = 0;
    for (const auto& l : *learners) sittings += l.exams.size();
    const std::string text = lessons::xapiStatementsJson(*learners, {}, options, {});
    if (auto ok = writeFileAtomically(*out, text + "\n"); !ok) return reportError("xapi: " + ok.error().message);
    terminalPrintf("wrote %s: statements of %s of class %s\n", out->c_str(),
                   str::countOf(long(sittings), "graded exam sitting").c_str(), code->c_str());
    return 0;
  }
  auto session = LearningSession::open(args->db(), true);
  if (!session) return reportError("xapi: " + session.error().message);
  std::vector<lessons::LearnerRecords> learners;
  std::vector<lessons::StudyRatings> studies;
  std::size_t records = 0;
  if (const auto studyId = args->value("study")) {
    auto protocol = db::findStudy((*session)->database(), *studyId);
    if (!protocol) return reportError("xapi: " + protocol.error().message);
    if (!*protocol) return reportError("xapi: no study '" + *studyId + "' in " + db::pathOf((*session)->database()));
    auto rows = db::studyResponseRows((*session)->database(), **protocol);
    if (!rows) return reportError("xapi: " + rows.error().message);
    records = rows->size();
    studies.push_back({**protocol, std::move(*rows)});
  } else {
    std::vector<lessons::User> users;
    if (const auto name = args->user()) {
      auto user = (*session)->user(*name, LearningSession::NewUser::Refuse);
      if (!user) return reportError("xapi: " + user.error().message);
      users.push_back(*user);
    } else {
      auto all = (*session)->users().users();
      if (!all) return reportError("xapi: " + all.error().message);
      users = std::move(*all);
    }
    for (const lessons::User& u : users) {
      auto r = recordsOf(**session, u);
      if (!r) return reportError("xapi: " + r.error().message);
      records += r->reviews.size() + r->attempts.size() + r->exams.size();
      for (const auto& e : r->exams) records += e.items.size();
      for (const auto& [attempt, responses] : r->responses) records += responses.size();
      learners.push_back(std::move(*r));
    }
  }
  const std::string text = lessons::xapiStatementsJson(learners, studies, options, answeredQuestions(**session, learners));
  if (auto ok = writeFileAtomically(*out, text + "\n"); !ok) return reportError("xapi: " + ok.error().message);
  terminalPrintf("wrote %s: statements of %s\n", out->c_str(),
              args->value("study") ? str::countOf(long(records), "rating").c_str()
                                   : (str::countOf(long(learners.size()), "user") + ", " +
                                      str::countOf(long(records), "attempt or answer", "attempts and answers"))
                                         .c_str());
  return 0;
}

}  // namespace at::app
