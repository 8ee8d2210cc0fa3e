// Learning records as xAPI statements (Experience API 1.0.3), the JSON a learning record store
// (LRS) or an LMS takes on POST /statements: each answer (lesson or review) an `answered`
// statement on a cmi.interaction activity (locate "other", identify/relation "choice", name
// "fill-in", order "sequencing"), each lesson attempt `attempted` and, when finished, `completed`
// with its score, and each preference-study rating an `answered` statement on a `likert`
// interaction whose scale is the study's.
//
// Statement ids are name-based UUIDs of what the record is (user, question, time, record id), so
// exporting the same records again gives the same ids and an LRS keeps each statement once.
// Actors are the pseudonyms (an account on `homePage`), never a real identity.
#pragma once

#include <map>
#include <string>
#include <string_view>
#include <vector>

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

// One learner's records, as the repositories give them.
struct LearnerRecords {
  User user;
  std::vector<Attempt> attempts;
  std::map<std::int64_t, std::vector<Response>> responses;  // by attempt id
  std::vector<ReviewResponse> reviews;
};

struct StudyRatings {
  quiz::StudyProtocol protocol;
  std::vector<quiz::StudyResponseRow> rows;
};

// An Invalid error naming the option when homePage or activityBase is not an http(s) URL.
Status checkXapiOptions(const XapiOptions& options);

// Every statement of `learners` and `studies`, as a JSON array (oldest first per learner).
std::string xapiStatementsJson(const std::vector<LearnerRecords>& learners, const std::vector<StudyRatings>& studies,
                               const XapiOptions& options);

// A UUID (version 8, RFC 9562: the first 122 bits of SHA-256 of `name`) — the same name, the same id.
std::string nameBasedUuid(std::string_view name);

}  // namespace at::lessons
