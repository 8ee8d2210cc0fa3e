#include "db/study_withdrawal.h"

#include "database.h"
#include "server_refusal.h"
#include "study_server_writes.h"

namespace at::db {

const char* toString(StudyWithdrawalKind kind) {
  return kind == StudyWithdrawalKind::Excluded ? "excluded" : "withdrawn";
}

Status setStudyOwner(Database& db, const std::string& studyId, const std::string& owner) {
  return db.writeTransaction([&](Database& d) -> Status {
    if (detail::studyWritesThroughServer(d)) return detail::setStudyOwnerOnServer(d, studyId, owner);
    auto s = d.prepare("UPDATE studies SET owner = ?2 WHERE id = ?1");
    if (!s) return tl::unexpected(s.error());
    s->bind(1, studyId).bind(2, owner);
    if (auto done = s->run(); !done) return done;
    if (d.changes() == 0) return fail(ErrorKind::NotFound, "no study '" + studyId + "' in " + d.path());
    return {};
  });
}

Result<std::string> studyOwner(Database& db, const std::string& studyId) {
  auto s = db.prepare("SELECT owner FROM studies WHERE id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, studyId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::NotFound, "no study '" + studyId + "' in " + db.path() + (db.backend() == Backend::Postgres ? " that you own" : ""));
  return s->text(0);
}

Status withdrawStudyParticipant(Database& db, const std::string& studyId, const std::string& participantId,
                                StudyWithdrawalKind kind, const std::string& reason, const std::optional<std::string>& by) {
  return db.writeTransaction([&](Database& d) -> Status {
    if (d.backend() == Backend::Postgres) {
      auto s = d.prepare("SELECT at_withdraw_participant(?1, ?2, ?3, ?4, ?5)");
      if (!s) return tl::unexpected(s.error());
      s->bind(1, studyId).bind(2, participantId).bind(3, toString(kind)).bind(4, reason).bind(5, by.value_or(""));
      auto row = s->step();
      if (!row) return tl::unexpected(serverRefusal(row.error()));
      return {};
    }
    // One person's file: the same change and its audit row, in one transaction.
    if (auto owner = studyOwner(d, studyId); !owner) return tl::unexpected(owner.error());
    if (reason.find_first_not_of(" \t\r\n") == std::string::npos)
      return fail("a withdrawal or exclusion needs its reason");
    auto s = d.prepare(
        "UPDATE study_participants SET withdrawn_at = strftime('%Y-%m-%dT%H:%M:%fZ', 'now'), withdrawal_kind = ?3,"
        " withdrawal_reason = ?4 WHERE study_id = ?1 AND participant_id = ?2 AND withdrawn_at IS NULL");
    if (!s) return tl::unexpected(s.error());
    s->bind(1, studyId).bind(2, participantId).bind(3, toString(kind)).bind(4, reason);
    if (auto done = s->run(); !done) return done;
    if (d.changes() == 0)
      return fail(ErrorKind::NotFound, "study '" + studyId + "' has no current participant '" + participantId + "'");
    auto audit = d.prepare(
        "INSERT INTO class_audit (actor, login, action, class_code, target, old_value, new_value, reason)"
        " VALUES (?1, ?1, ?2, '', ?3, 'participant', ?4, ?5)");
    if (!audit) return tl::unexpected(audit.error());
    audit->bind(1, by.value_or("")).bind(2, std::string("study_") + toString(kind)).bind(3, studyId + " " + participantId);
    audit->bind(4, toString(kind)).bind(5, reason);
    return audit->run();
  });
}

Result<std::vector<StudyWithdrawal>> studyWithdrawals(Database& db, const std::string& studyId) {
  auto s = db.prepare(
      "SELECT participant_id, group_name, withdrawal_kind, withdrawal_reason, withdrawn_at FROM study_participants"
      " WHERE study_id = ?1 AND withdrawn_at IS NOT NULL ORDER BY enrolment_index");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, studyId);
  std::vector<StudyWithdrawal> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    out.push_back({r.text(0), r.text(1),
                   r.text(2) == "excluded" ? StudyWithdrawalKind::Excluded : StudyWithdrawalKind::Withdrawn, r.text(3),
                   r.text(4)});
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

}  // namespace at::db
