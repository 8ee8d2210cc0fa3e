// Who owns a preference study, and the withdrawal (consent withdrawn) or exclusion of its
// participants. A withdrawn or excluded participant's rows stay where they are, with the reason,
// but every export (responses, REDCap, xAPI) and the Table 2 summary leave them out; `study
// status` lists them with the reason. On a class server only the study's owner — the coordinator
// whose login registered it with `--owner` — reads the study and withdraws its participants,
// through an audited server function (class_audit: study_withdrawn / study_excluded); on a SQLite
// file the change and its audit row are written together.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "db/connection.h"

namespace at::db {

enum class StudyWithdrawalKind { Withdrawn, Excluded };
const char* toString(StudyWithdrawalKind kind);  // "withdrawn", "excluded"

// Sets the study's owner (a class server login; "" = the database's administrator). On a server
// the administrator names anyone; the owner's login may hand the study to another coordinator's
// login (audited, through at_set_study_owner). NotFound when there is no such study.
Status setStudyOwner(Database& db, const std::string& studyId, const std::string& owner);
Result<std::string> studyOwner(Database& db, const std::string& studyId);

// Withdraws or excludes a current participant with the reason. `by`: who acts (on a server a
// login acts as itself; the administrator may name the owner it acts for; on a SQLite file it is
// recorded as given). Errors: no such study or current participant, an empty reason, not the owner.
Status withdrawStudyParticipant(Database& db, const std::string& studyId, const std::string& participantId,
                                StudyWithdrawalKind kind, const std::string& reason, const std::optional<std::string>& by);

struct StudyWithdrawal {
  std::string participantId, group;
  StudyWithdrawalKind kind = StudyWithdrawalKind::Withdrawn;
  std::string reason, at;  // at: ISO-8601 UTC
};
// The study's withdrawn and excluded participants, in enrolment order.
Result<std::vector<StudyWithdrawal>> studyWithdrawals(Database& db, const std::string& studyId);

}  // namespace at::db
