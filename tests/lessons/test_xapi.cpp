// Learning records as xAPI statements, checked against the rules of the xAPI 1.0.3 specification
// (Part Two: statement properties, agents' identifiers, interaction activities, results, ISO 8601
// times and durations) rather than against a copy of the output.
#include <doctest/doctest.h>

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "core/name_uuid.h"
#include "lessons/xapi.h"
#include "test_support.h"

using namespace at;
using namespace at::lessons;
using json = nlohmann::json;
namespace fs = std::filesystem;

namespace {

// RFC 4122: versions 1-5, variant 10xx (what the ADL conformance suite requires of an LRS).
const std::regex kUuid("^[0-9a-f]{8}-[0-9a-f]{4}-[1-5][0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}$");
const std::regex kTimestamp(R"(^\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d+)?Z$)");
const std::regex kDuration(R"(^PT(\d+(\.\d+)?S)$)");
const std::regex kAbsoluteIri(R"(^[a-z][a-z0-9+.-]*:[^\s]+$)");
const std::set<std::string> kInteractionTypes = {"true-false", "choice",      "fill-in", "long-fill-in", "matching",
                                                 "performance", "sequencing", "likert",  "numeric",      "other"};

GradedAnswer graded(const std::string& question, quiz::Answer answer, bool correct, std::int64_t at) {
  GradedAnswer g;
  g.questionId = question;
  g.structureId = "cochlea";
  g.answer = std::move(answer);
  g.correct = correct;
  g.score = correct ? 1 : 0.5;
  g.latencyMs = 2350;
  g.render = {"cochlea_wdt", "wdt", 0.4, 1.6, 1.0};
  g.answeredAt = at;
  return g;
}

std::vector<LearnerRecords> learners() {
  LearnerRecords r;
  r.user = {7, "sam", Role::Student, "first-year"};
  r.attempts = {{11, 7, "inner_ear", LessonMode::Guided, 1'790'000'000, 1'790'000'600, 0.75},
                {12, 7, "facial nerve/1", LessonMode::QuizOnly, 1'790'001'000, std::nullopt, 0}};
  quiz::Answer pick, choice, text, order;
  pick.pick = quiz::Pick{.structure = "cochlea", .distanceMm = 0.4, .pixel = std::nullopt, .view = ""};
  choice.choice = 2;
  text.text = "vestibule";
  order.order = std::vector<std::string>{"malleus", "incus", "stapes"};
  auto response = [](GradedAnswer g, int step) {
    Response x;
    static_cast<GradedAnswer&>(x) = std::move(g);
    x.attemptId = 11;
    x.stepIndex = step;
    return x;
  };
  r.responses[11] = {response(graded("inner_ear.locate_cochlea", pick, true, 1'790'000'100), 4),
                     response(graded("inner_ear.identify_vestibule", choice, false, 1'790'000'200), 5),
                     response(graded("inner_ear.name_vestibule", text, true, 1'790'000'300), 6),
                     response(graded("inner_ear.order_ossicles", order, false, 1'790'000'400), 7)};
  ReviewResponse review;
  static_cast<GradedAnswer&>(review) = graded("inner_ear.name_vestibule", text, true, 1'790'086'400);
  review.id = 3;
  review.userId = 7;
  r.reviews = {review};
  return {r};
}

// The choice and order questions of learners() as they were asked.
XapiQuestions questions() {
  XapiQuestions q;
  XapiQuestion identify;
  identify.resolved.question.id = "inner_ear.identify_vestibule";
  identify.resolved.question.kind = quiz::QuestionKind::Identify;
  identify.resolved.choices = {"cochlea", "vestibule", "stapes"};
  identify.resolved.keyChoice = 1;
  identify.names = {{"cochlea", "Cochlea"}, {"vestibule", "Vestibule"}, {"stapes", "Stapes"},
                    {"malleus", "Malleus"}, {"incus", "Incus"}};
  q["inner_ear.identify_vestibule"] = identify;
  XapiQuestion order = identify;
  order.resolved.question.id = "inner_ear.order_ossicles";
  order.resolved.question.kind = quiz::QuestionKind::Order;
  order.resolved.choices = {"stapes", "malleus", "incus"};
  order.resolved.keyChoice = -1;
  order.resolved.keyOrder = {"malleus", "incus", "stapes"};
  q["inner_ear.order_ossicles"] = order;
  return q;
}

// A finished exam attempt of learners()'s user: an identify item answered right, a locate item
// answered wrong, one item not answered.
ExamRecord exam() {
  ExamRecord e;
  e.attempt = {21, 7, "temporal_bone.practical", "temporal_bone", 1'790'002'000, 1'790'002'900, 1'790'002'500, 0.5, false};
  ExamItem identify;
  identify.position = 0;
  identify.question.question.id = "temporal_bone.practical.identify.cochlea";
  identify.question.question.kind = quiz::QuestionKind::Identify;
  identify.question.question.target = "cochlea";
  identify.question.choices = {"stapes", "cochlea", "incus", "malleus"};
  identify.question.keyChoice = 1;
  identify.answer = quiz::Answer{};
  identify.answer->choice = 1;
  identify.correct = true;
  identify.score = 1;
  identify.latencyMs = 4000;
  identify.answeredAt = 1'790'002'100;
  ExamItem locate;
  locate.position = 1;
  locate.question.question.id = "temporal_bone.practical.locate.stapes";
  locate.question.question.kind = quiz::QuestionKind::Locate;
  locate.question.question.target = "stapes";
  locate.answer = quiz::Answer{};
  locate.answer->pick = quiz::Pick{.structure = "incus", .distanceMm = 2.5, .pixel = std::nullopt, .view = ""};
  locate.answeredAt = 1'790'002'200;
  ExamItem unanswered;
  unanswered.position = 2;
  unanswered.question.question.id = "temporal_bone.practical.name.incus";
  e.items = {identify, locate, unanswered};
  return e;
}

std::vector<StudyRatings> studies() {
  StudyRatings s;
  s.protocol.id = "wdt_vs_bare";
  s.protocol.title = "WDT vs bare";
  s.protocol.items = {{"shape", "The shape of the structure is clearer"}, {"context", "Its surroundings are clearer"}};
  s.protocol.scale.anchors = {{1, "prefer A"}, {3, "no preference"}, {5, "prefer B"}};
  for (int i = 0; i < 4; ++i) {
    quiz::StudyResponseRow row;
    row.participantId = i < 2 ? "p01" : "p02";
    row.group = "medical";
    row.structure = "cochlea";
    row.item = i % 2 ? "context" : "shape";
    row.ratingAb = 1 + i;
    row.rating = 5 - i;
    row.aCondition = "bare";
    row.responseMs = 4100;
    row.timestampUtc = "2026-11-22T05:01:02Z";
    s.rows.push_back(row);
  }
  return {s};
}

void checkStatement(const json& s) {
  INFO(s.dump());
  REQUIRE(s.is_object());
  CHECK(std::regex_match(s.at("id").get<std::string>(), kUuid));
  // Actor: an Agent with exactly one inverse functional identifier, here an account.
  const json& actor = s.at("actor");
  CHECK(actor.at("objectType") == "Agent");
  int identifiers = 0;
  for (const char* ifi : {"mbox", "mbox_sha1sum", "openid", "account"}) identifiers += actor.contains(ifi);
  CHECK(identifiers == 1);
  CHECK(actor.at("account").at("homePage").get<std::string>().rfind("http", 0) == 0);
  CHECK_FALSE(actor.at("account").at("name").get<std::string>().empty());
  // Verb: an IRI and a language map.
  CHECK(std::regex_match(s.at("verb").at("id").get<std::string>(), kAbsoluteIri));
  CHECK(s.at("verb").at("display").is_object());
  // Object: an Activity with an absolute IRI id (no spaces, percent-encoded).
  const json& object = s.at("object");
  CHECK(object.at("objectType") == "Activity");
  CHECK(std::regex_match(object.at("id").get<std::string>(), kAbsoluteIri));
  const json& definition = object.at("definition");
  CHECK(std::regex_match(definition.at("type").get<std::string>(), kAbsoluteIri));
  if (definition.contains("interactionType")) {
    CHECK(definition.at("type") == "http://adlnet.gov/expapi/activities/cmi.interaction");
    CHECK(kInteractionTypes.count(definition.at("interactionType").get<std::string>()) == 1);
  }
  if (s.contains("result")) {
    const json& result = s.at("result");
    if (result.contains("score")) {
      const json& score = result.at("score");
      const double scaled = score.at("scaled").get<double>();
      CHECK(scaled >= -1);
      CHECK(scaled <= 1);
      CHECK(score.at("raw").get<double>() >= score.at("min").get<double>());
      CHECK(score.at("raw").get<double>() <= score.at("max").get<double>());
    }
    if (result.contains("duration")) CHECK(std::regex_match(result.at("duration").get<std::string>(), kDuration));
    if (result.contains("response")) CHECK(result.at("response").is_string());
  }
  if (s.contains("timestamp")) CHECK(std::regex_match(s.at("timestamp").get<std::string>(), kTimestamp));
  const json& context = s.at("context");
  if (context.contains("registration")) CHECK(std::regex_match(context.at("registration").get<std::string>(), kUuid));
  if (context.contains("contextActivities"))
    for (const json& parent : context.at("contextActivities").at("parent"))
      CHECK(std::regex_match(parent.at("id").get<std::string>(), kAbsoluteIri));
  if (context.contains("extensions"))
    for (const auto& [key, value] : context.at("extensions").items()) CHECK(std::regex_match(key, kAbsoluteIri));
}

}  // namespace

TEST_CASE("Answers, attempts and study ratings become valid xAPI statements; a rating is a likert interaction") {
  XapiOptions options;
  options.homePage = "https://lms.example.edu";
  options.activityBase = "https://lms.example.edu/anatomy";
  options.appVersion = "0.1.0";
  const json statements = json::parse(xapiStatementsJson(learners(), studies(), options, questions()));
  REQUIRE(statements.is_array());
  // 2 attempted + 1 completed + 4 lesson answers + 1 review answer + 4 ratings.
  REQUIRE(statements.size() == 12);
  std::set<std::string> ids;
  std::map<std::string, int> verbs, interactions;
  for (const json& s : statements) {
    checkStatement(s);
    ids.insert(s.at("id").get<std::string>());
    ++verbs[s.at("verb").at("display").at("en-US").get<std::string>()];
    if (s.at("object").at("definition").contains("interactionType"))
      ++interactions[s.at("object").at("definition").at("interactionType").get<std::string>()];
  }
  CHECK(ids.size() == statements.size());
  CHECK(verbs == std::map<std::string, int>{{"answered", 9}, {"attempted", 2}, {"completed", 1}});
  CHECK(interactions ==
        std::map<std::string, int>{{"other", 1}, {"choice", 1}, {"fill-in", 2}, {"sequencing", 1}, {"likert", 4}});

  // The lesson's id has a space and a slash: one percent-encoded path segment.
  CHECK(statements[6].at("object").at("id") == "https://lms.example.edu/anatomy/lessons/facial%20nerve%2F1");
  // Answers: success, score, response in xAPI's formats, the time taken, the lesson as parent.
  for (const json& s : statements) {
    const json& d = s.at("object").at("definition");
    if (d.value("interactionType", "") == "choice") {
      // The choices offered (ids with the names shown), the key, and the chosen choice's id.
      REQUIRE(d.at("choices").size() == 3);
      CHECK(d.at("choices")[2].at("id") == "stapes");
      CHECK(d.at("choices")[2].at("description").at("en-US") == "Stapes");
      CHECK(d.at("correctResponsesPattern") == json::array({"vestibule"}));
      CHECK(s.at("result").at("response") == "stapes");
    }
    if (d.value("interactionType", "") == "sequencing") {
      CHECK(d.at("choices").size() == 3);
      CHECK(d.at("correctResponsesPattern") == json::array({"malleus[,]incus[,]stapes"}));
      CHECK(s.at("result").at("response") == "malleus[,]incus[,]stapes");
      CHECK(s.at("result").at("success") == false);
      CHECK(s.at("result").at("score").at("scaled") == 0.5);
      CHECK(s.at("result").at("duration") == "PT2.35S");
      CHECK(s.at("context").at("contextActivities").at("parent")[0].at("id") ==
            "https://lms.example.edu/anatomy/lessons/inner_ear");
      CHECK(s.at("timestamp") == "2026-09-21T14:20:00Z");
    }
    if (s.at("verb").at("display").at("en-US") == "completed") {
      CHECK(s.at("result").at("completion") == true);
      CHECK(s.at("result").at("score").at("scaled") == 0.75);
      CHECK(s.at("result").at("duration") == "PT600.00S");
    }
    if (d.value("interactionType", "") == "likert") {
      // The study's scale, 1..5, every point with a description; the response is one of its ids.
      const json& scale = d.at("scale");
      REQUIRE(scale.size() == 5);
      std::set<std::string> scaleIds;
      for (const json& point : scale) {
        scaleIds.insert(point.at("id").get<std::string>());
        CHECK_FALSE(point.at("description").at("en-US").get<std::string>().empty());
      }
      CHECK(scale[0].at("description").at("en-US") == "prefer A");
      CHECK(scaleIds.count(s.at("result").at("response").get<std::string>()) == 1);
      CHECK(s.at("context").contains("registration"));
      CHECK(s.at("actor").at("account").at("name").get<std::string>().rfind("p0", 0) == 0);
    }
  }
  // One participant, one registration; another participant, another.
  CHECK(statements[8].at("context").at("registration") == statements[9].at("context").at("registration"));
  CHECK(statements[8].at("context").at("registration") != statements[10].at("context").at("registration"));

  // Exported again: the same ids (a record store keeps each statement once).
  const json again = json::parse(xapiStatementsJson(learners(), studies(), options, questions()));
  for (std::size_t i = 0; i < statements.size(); ++i) CHECK(again[i].at("id") == statements[i].at("id"));
}

TEST_CASE("xAPI options must be web addresses, and name-based UUIDs are stable RFC 4122 version-5 UUIDs") {
  XapiOptions options;
  CHECK(checkXapiOptions(options));
  options.homePage = "lms.example.edu";
  auto bad = checkXapiOptions(options);
  REQUIRE_FALSE(bad);
  CHECK(bad.error().message == "xAPI home page 'lms.example.edu' is not an http:// or https:// URL");
  CHECK(nameBasedUuid("a") == nameBasedUuid("a"));
  CHECK(nameBasedUuid("a") != nameBasedUuid("b"));
  CHECK(std::regex_match(nameBasedUuid("a"), kUuid));
  CHECK(nameBasedUuid("a")[14] == '5');
  // Python's uuid.uuid5(uuid.NAMESPACE_URL, …) and uuid5(NAMESPACE_DNS, "python.org").
  CHECK(nameBasedUuid("http://localhost/anatomy-tutor") == "86b277b0-b0cd-5252-b60e-23cacf6f77bd");
  CHECK(nameBasedUuid("") == "1b4db7eb-4057-5ddf-91e0-36dec72071f5");
  CHECK(uuidV5("6ba7b810-9dad-11d1-80b4-00c04fd430c8", "python.org") == "886313e1-3b8a-5372-9b90-0c9aee199e5d");
  CHECK_FALSE(uuidV5("not a uuid", "x"));
}

TEST_CASE("An exam attempt becomes attempted, one answered statement per answered item, and completed with its pass") {
  XapiOptions options;
  std::vector<LearnerRecords> records = learners();
  records[0].attempts.clear();
  records[0].responses.clear();
  records[0].reviews.clear();
  records[0].exams = {exam()};
  const json statements = json::parse(xapiStatementsJson(records, {}, options));
  REQUIRE(statements.size() == 4);
  for (const json& s : statements) checkStatement(s);
  CHECK(statements[0].at("verb").at("display").at("en-US") == "attempted");
  CHECK(statements[0].at("object").at("definition").at("type") == "http://adlnet.gov/expapi/activities/assessment");
  const json& identify = statements[1];
  CHECK(identify.at("object").at("definition").at("interactionType") == "choice");
  CHECK(identify.at("object").at("definition").at("correctResponsesPattern") == json::array({"cochlea"}));
  CHECK(identify.at("result").at("response") == "cochlea");
  CHECK(identify.at("context").at("contextActivities").at("parent")[0].at("id") == statements[0].at("object").at("id"));
  CHECK(statements[2].at("result").at("response") == "incus");
  CHECK(statements[2].at("result").at("success") == false);
  CHECK(statements[3].at("verb").at("display").at("en-US") == "completed");
  CHECK(statements[3].at("result").at("score").at("scaled") == 0.5);
  CHECK(statements[3].at("result").at("success") == false);
}

TEST_CASE("Every statement passes Learning Locker's xAPI validator (npm @learninglocker/xapi-validation under Node.js)") {
  int status = 0;
  test::runCommand("command -v node", status);
  if (status != 0) {
    at::test::skipf("the xAPI validator needs Node.js (Debian package 'nodejs'; scripts/install-deps.sh)");
    return;
  }
  test::TempDir dir;
  XapiOptions options;
  options.appVersion = "0.1.0";
  std::vector<LearnerRecords> records = learners();
  records[0].exams = {exam()};
  const fs::path file = dir / "statements.json";
  std::ofstream(file) << xapiStatementsJson(records, studies(), options, questions());
  const std::string out = test::runCommand("bash '" + (test::sourceDir() / "scripts/xapi-validator.sh").string() +
                                             "' validate '" + file.string() + "' 2>&1",
                                         status);
  INFO(out);
  CHECK(status == 0);
  CHECK(out.find("16 statement(s), 0 problem(s)") != std::string::npos);
  // The validator does refuse: a version-8 id and a choice without its id list are reported.
  json broken = json::parse(test::readFile(file));
  broken[0]["id"] = "0f3ad5e4-9b1c-8d2e-a3f4-5b6c7d8e9f00";
  broken[1]["verb"].erase("id");
  std::ofstream(dir / "broken.json") << broken.dump();
  const std::string refused = test::runCommand("bash '" + (test::sourceDir() / "scripts/xapi-validator.sh").string() +
                                                 "' validate '" + (dir / "broken.json").string() + "' 2>&1",
                                             status);
  INFO(refused);
  CHECK(status == 1);
  CHECK(refused.find("[0]: id 0f3ad5e4") != std::string::npos);
  CHECK(refused.find("[1]: statement.verb.id") != std::string::npos);
}
