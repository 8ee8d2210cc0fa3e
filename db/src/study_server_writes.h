// A study's writes on a class server (PostgreSQL): each is one call of the server's audited
// functions (study_writes_sql.cpp), which decide who may write — the study's owner, or the
// administrator. Private to db/; the study store calls them inside its own transactions, and keeps
// its direct statements for SQLite files. Refusals come back as the server's reason
// (serverRefusal), with their kind.
#pragma once

#include <optional>
#include <string>

#include "database.h"
#include "db/study_store.h"
#include "quiz/study_protocol.h"

namespace at::db::detail {

// Whether `d` is a class server whose schema has these functions (a PostgreSQL database opened at
// an older version, as the migration tests do, is written directly like a file).
bool studyWritesThroughServer(Database& d);

// Stores or updates the study's row; `owner` "" keeps the owner (a login always owns what it
// registers; only the administrator names another).
Status registerStudyOnServer(Database& d, const quiz::StudyProtocol& protocol, const std::string& owner);
Status setStudyOwnerOnServer(Database& d, const std::string& studyId, const std::string& owner);
// The study's next counterbalancing row (its own short transaction is the caller's).
Result<int> drawStudyRowOnServer(Database& d, const std::string& studyId);
// Enrols the participant on row `drawn` with the trials of that row's plan, or (when they are
// enrolled already) resumes them; `drawn` may be empty only for a participant already enrolled.
Status enrolOnServer(Database& d, const quiz::StudyProtocol& protocol, const std::string& participantId,
                     const std::string& group, std::optional<int> drawn);
Status recordRatingOnServer(Database& d, const StudyParticipant& participant, const RatingRecord& rating);
Status recordTrialViewingOnServer(Database& d, const StudyParticipant& participant, int position, double viewMsA,
                                  double viewMsB, int toggles, const std::string& comment, bool viewingMeasured);
Status completeParticipantOnServer(Database& d, const StudyParticipant& participant);

}  // namespace at::db::detail
