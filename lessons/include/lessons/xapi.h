// Learning records as xAPI statements (Experience API 1.0.3), the JSON a learning record store
// (LRS) or an LMS takes on POST /statements: each answer (lesson or review) an `answered`
// statement on a cmi.interaction activity (locate "other", identify/relation "choice", name
// "fill-in", order "sequencing"), each lesson attempt `attempted` and, when finished, `completed`
// with its score, each exam attempt `attempted` (and `completed` with its score and, when the exam
// has a pass mark, success) with an `answered` statement per answered item, and each
// preference-study rating an `answered` statement on a `likert` interaction whose scale is the
// study's. Choice and sequencing interactions carry the `choices` offered (structure ids, with
// the names shown) and the `correctResponsesPattern`; their responses are choice ids.
//
// Statement ids and registrations are name-based UUIDs (RFC 4122 version 5) of what the record is
// (user, question, time, record id), so exporting the same records again gives the same ids and
// an LRS keeps each statement once.
// Actors are the pseudonyms (an account on `homePage`), never a real identity.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "lessons/exam.h"
#include "lessons/repositories.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"

namespace at::lessons {

struct XapiOptions {
  // The system the pseudonyms are accounts of (an IRL: the school's LMS, the class server's site).
  std::string homePage = "http://localhost/anatomy-tutor";
  // Where activity ids live: <activityBase>/questions/<id>, /lessons/<id>, /studies/<id>/….
  std::string activityBase = "http://localhost/anatomy-tutor/xapi";
  std::string appVersion;  // context.extensions, when given
};

// One exam attempt with its items (each item carries its question as it was asked: choices, keys).
struct ExamRecord {
  ExamAttempt attempt;
  std::vector<ExamItem> items;
};

// One learner's records, as the repositories give them.
struct LearnerRecords {
  User user;
  std::vector<Attempt> attempts;
  std::map<std::int64_t, std::vector<Response>> responses;  // by attempt id
  std::vector<ReviewResponse> reviews;
  std::vector<ExamRecord> exams;
};

// What a lesson or review question offered, for its interaction definition: the question as
// resolved on its dataset (the choices in the order shown and the key), and the structures'
// names shown. A choice or order answer to a question not given here is exported as an "other"
// interaction with its response as given.
struct XapiQuestion {
  quiz::ResolvedQuestion resolved;
  std::map<std::string, std::string> names;  // structure id → name shown (missing: the id)
};
using XapiQuestions = std::map<std::string, XapiQuestion>;  // by question id

struct StudyRatings {
  quiz::StudyProtocol protocol;
  std::vector<quiz::StudyResponseRow> rows;
};

// An Invalid error naming the option when homePage or activityBase is not an http(s) URL.
Status checkXapiOptions(const XapiOptions& options);

// Every statement of `learners` and `studies`, as a JSON array (oldest first per learner).
std::string xapiStatementsJson(const std::vector<LearnerRecords>& learners, const std::vector<StudyRatings>& studies,
                               const XapiOptions& options, const XapiQuestions& questions = {});

// A UUID (RFC 4122 version 5 of `name` in the URL namespace) — the same name, the same id.
std::string nameBasedUuid(std::string_view name);

}  // namespace at::lessons
