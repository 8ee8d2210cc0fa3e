#include "db/study_store.h"

#include <algorithm>
#include <cctype>
#include <map>

#include "database.h"
#include "quiz/study_design.h"
#include "study_rows.h"
#include "study_server_writes.h"
#include "utc_time.h"

namespace at::db {

namespace detail {

bool sameDesign(const quiz::StudyProtocol& a, const quiz::StudyProtocol& b) {
  return a.structures == b.structures && a.conditions == b.conditions && a.items == b.items && a.seed == b.seed &&
         a.scale == b.scale && a.presets == b.presets;
}

Result<int> participantCount(Database& db, const std::string& studyId) {
  auto st = db.prepare("SELECT count(*) FROM study_participants WHERE study_id = ?1");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, studyId);
  auto row = st->step();
  if (!row) return tl::unexpected(row.error());
  return st->integer(0);
}

Status storeStudyRow(Database& db, const quiz::StudyProtocol& protocol) {
  if (studyWritesThroughServer(db)) return registerStudyOnServer(db, protocol, "");
  auto st = db.prepare(
      "INSERT INTO studies (id, title, dataset, seed, json) VALUES (?1, ?2, ?3, ?4, ?5) "
      "ON CONFLICT(id) DO UPDATE SET title = excluded.title, dataset = excluded.dataset, seed = excluded.seed, "
      "json = excluded.json");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, protocol.id)
      .bind(2, protocol.title)
      .bind(3, protocol.dataset)
      .bind(4, std::int64_t(protocol.seed))
      .bind(5, quiz::serialiseStudyProtocol(protocol));
  return st->run();
}

}  // namespace detail

namespace {

using detail::participantCount;
using detail::sameDesign;

Result<StudyParticipant> loadParticipant(Database& db, const std::string& studyId, const std::string& participantId) {
  auto st = db.prepare(
      "SELECT group_name, enrolment_index, session, completed_at IS NOT NULL FROM study_participants "
      "WHERE study_id = ?1 AND participant_id = ?2");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, studyId).bind(2, participantId);
  auto row = st->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail("study '" + studyId + "' has no participant '" + participantId + "'");
  StudyParticipant p;
  p.studyId = studyId;
  p.participantId = participantId;
  p.group = st->text(0);
  p.enrolmentIndex = st->integer(1);
  p.session = st->integer(2);
  p.complete = st->integer(3) != 0;

  auto trials = db.prepare(
      "SELECT position, structure, a_condition, b_condition, preset_a, preset_b, view_ms_a, view_ms_b, toggles, "
      "comment, viewing_measured FROM study_trials WHERE study_id = ?1 AND participant_id = ?2 ORDER BY position");
  if (!trials) return tl::unexpected(trials.error());
  trials->bind(1, studyId).bind(2, participantId);
  while (true) {
    auto r = trials->step();
    if (!r) return tl::unexpected(r.error());
    if (!*r) break;
    StudyTrial t;
    t.position = trials->integer(0);
    t.structure = trials->text(1);
    t.aCondition = trials->text(2);
    t.bCondition = trials->text(3);
    t.presetA = trials->text(4);
    t.presetB = trials->text(5);
    t.viewMsA = trials->real(6);
    t.viewMsB = trials->real(7);
    t.toggles = trials->integer(8);
    t.comment = trials->optionalText(9).value_or("");
    t.viewingMeasured = trials->integer(10) != 0;
    p.trials.push_back(t);
  }
  auto rated = db.prepare("SELECT position, item FROM study_ratings WHERE study_id = ?1 AND participant_id = ?2");
  if (!rated) return tl::unexpected(rated.error());
  rated->bind(1, studyId).bind(2, participantId);
  while (true) {
    auto r = rated->step();
    if (!r) return tl::unexpected(r.error());
    if (!*r) break;
    const int position = rated->integer(0);
    if (position >= 0 && position < int(p.trials.size())) p.trials[std::size_t(position)].ratedItems.insert(rated->text(1));
  }
  return p;
}

}  // namespace

std::optional<std::size_t> StudyParticipant::nextTrial(std::size_t itemCount) const {
  for (std::size_t i = 0; i < trials.size(); ++i)
    if (trials[i].ratedItems.size() < itemCount) return i;
  return std::nullopt;
}

Status saveStudy(Database& db, const quiz::StudyProtocol& protocol) {
  return db.writeTransaction([&](Database& d) -> Status {
    auto existing = findStudy(d, protocol.id);
    if (!existing) return tl::unexpected(existing.error());
    if (*existing && !sameDesign(**existing, protocol)) {
      auto count = participantCount(d, protocol.id);
      if (!count) return tl::unexpected(count.error());
      if (*count > 0)
        return fail("study '" + protocol.id + "' already has " + std::to_string(*count) +
                    " participant(s); its structures, conditions, items, scale and seed cannot change (give the new "
                    "design another id)");
    }
    return detail::storeStudyRow(d, protocol);
  });
}

Result<std::optional<quiz::StudyProtocol>> findStudy(Database& db, const std::string& studyId) {
  auto st = db.prepare("SELECT json FROM studies WHERE id = ?1");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, studyId);
  auto row = st->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<quiz::StudyProtocol>{};
  auto p = quiz::parseStudyProtocol(st->text(0), "stored study '" + studyId + "'");
  if (!p) return tl::unexpected(p.error());
  return std::optional<quiz::StudyProtocol>{*p};
}

Result<std::vector<quiz::StudyProtocol>> listStudies(Database& db) {
  auto st = db.prepare("SELECT id, json FROM studies ORDER BY id");
  if (!st) return tl::unexpected(st.error());
  std::vector<quiz::StudyProtocol> out;
  while (true) {
    auto row = st->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    auto p = quiz::parseStudyProtocol(st->text(1), "stored study '" + st->text(0) + "'");
    if (!p) return tl::unexpected(p.error());
    out.push_back(*p);
  }
  return out;
}

namespace {

// What one participant's writes lock on a server (Database::keyedWriteTransaction): their rows
// only, so lab machines recording different participants do not wait for each other.
std::string participantKey(const std::string& studyId, const std::string& participantId) {
  return "study participant|" + studyId + "|" + participantId;
}

// On a server: the study's next counterbalancing row, counted on (studies.next_enrolment), at
// least one past the highest row any participant has (rows merged in from other machines
// included); in a transaction of its own that locks the study's counter row for one statement.
// Drawn by the server's at_draw_study_row (only the study's owner draws), on a server whose schema
// has it.
Result<int> drawStudyRow(Database& db, const std::string& studyId) {
  int index = -1;
  const auto draw = [&](Database& d) -> Status {
    if (detail::studyWritesThroughServer(d)) {
      auto drawn = detail::drawStudyRowOnServer(d, studyId);
      if (!drawn) return tl::unexpected(drawn.error());
      index = *drawn;
      return {};
    }
    auto st = d.prepare(  // a server at an older schema version, written directly
        "UPDATE studies SET next_enrolment = GREATEST(next_enrolment, (SELECT coalesce(max(enrolment_index) + 1, 0)"
        " FROM study_participants WHERE study_id = ?1)) + 1 WHERE id = ?1 RETURNING next_enrolment - 1");
    if (!st) return tl::unexpected(st.error());
    st->bind(1, studyId);
    auto row = st->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return fail(ErrorKind::NotFound, "no study '" + studyId + "' in " + d.path());
    index = st->integer(0);
    return {};
  };
  auto done = db.keyedWriteTransaction("study rows|" + studyId, draw);
  if (!done) return tl::unexpected(done.error());
  return index;
}

}  // namespace

Result<StudyParticipant> enrolOrResume(Database& db, const quiz::StudyProtocol& protocol,
                                       const std::string& participantId, const std::string& group) {
  if (auto valid = validParticipantId(participantId); !valid) return tl::unexpected(valid.error());
  bool knownGroup = false;
  for (const auto& g : protocol.groups) knownGroup = knownGroup || g == group;
  if (!knownGroup) {
    std::string groups;
    for (const auto& g : protocol.groups) groups += (groups.empty() ? "" : ", ") + g;
    return fail("group '" + group + "' is not one of study '" + protocol.id + "''s groups (" + groups + ")");
  }
  // The enrolment index is the study's next counterbalancing row (drawStudyRow). On a server it is
  // drawn first, in a transaction of its own that locks only the study's counter row for one
  // UPDATE, so lab machines enrolling at once wait for each other that long, not for each other's
  // whole enrolment; the enrolment itself then locks only its participant's key. A draw whose
  // enrolment then fails (or finds the participant enrolled by another machine meanwhile) leaves
  // its row unused: the next participants take the rows after it. On SQLite (one writer) the row
  // is the participant count, taken inside the enrolment's transaction.
  const bool server = db.backend() == Backend::Postgres;
  std::optional<int> drawn;
  if (server) {
    auto known = db.prepare("SELECT 1 FROM study_participants WHERE study_id = ?1 AND participant_id = ?2");
    if (!known) return tl::unexpected(known.error());
    known->bind(1, protocol.id).bind(2, participantId);
    auto row = known->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) {
      auto index = drawStudyRow(db, protocol.id);
      if (!index) return tl::unexpected(index.error());
      drawn = *index;
    }
  }
  auto written = db.keyedWriteTransaction(participantKey(protocol.id, participantId), [&](Database& d) -> Status {
    if (server && detail::studyWritesThroughServer(d)) return detail::enrolOnServer(d, protocol, participantId, group, drawn);
    auto existing = d.prepare("SELECT group_name FROM study_participants WHERE study_id = ?1 AND participant_id = ?2");
    if (!existing) return tl::unexpected(existing.error());
    existing->bind(1, protocol.id).bind(2, participantId);
    auto row = existing->step();
    if (!row) return tl::unexpected(row.error());
    if (*row) {
      // A withdrawn or excluded participant is not resumed (db/study_withdrawal.h).
      auto withdrawn = d.prepare(
          "SELECT withdrawal_kind, withdrawal_reason FROM study_participants WHERE study_id = ?1 AND participant_id = ?2"
          " AND withdrawn_at IS NOT NULL");
      if (!withdrawn) return tl::unexpected(withdrawn.error());
      withdrawn->bind(1, protocol.id).bind(2, participantId);
      auto gone = withdrawn->step();
      if (!gone) return tl::unexpected(gone.error());
      if (*gone)
        return fail(ErrorKind::Conflict, "participant '" + participantId + "' was " + withdrawn->text(0) +
                                             " from study '" + protocol.id + "' (" + withdrawn->text(1) +
                                             "); nothing more is recorded for them");
      if (existing->text(0) != group)
        return fail("participant '" + participantId + "' is enrolled in group '" + existing->text(0) + "', not '" +
                    group + "'");
      auto bump = d.prepare("UPDATE study_participants SET session = session + 1 WHERE study_id = ?1 AND participant_id = ?2");
      if (!bump) return tl::unexpected(bump.error());
      bump->bind(1, protocol.id).bind(2, participantId);
      return bump->run();
    }
    std::optional<int> index = drawn;
    if (!index) {  // SQLite: the next row inside this transaction (one writer at a time anyway)
      auto count = participantCount(d, protocol.id);
      if (!count) return tl::unexpected(count.error());
      index = *count;
    }
    auto insert = d.prepare(
        "INSERT INTO study_participants (study_id, participant_id, group_name, enrolment_index) VALUES (?1, ?2, ?3, ?4)");
    if (!insert) return tl::unexpected(insert.error());
    insert->bind(1, protocol.id).bind(2, participantId).bind(3, group).bind(4, *index);
    if (auto s = insert->run(); !s) return s;
    auto trial = d.prepare(
        "INSERT INTO study_trials (study_id, participant_id, position, structure, a_condition, b_condition, preset_a, "
        "preset_b) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)");
    if (!trial) return tl::unexpected(trial.error());
    for (const quiz::TrialPlan& plan : quiz::planParticipant(protocol.structures.size(), std::size_t(*index), protocol.seed)) {
      const std::string& structure = protocol.structures[plan.structureIndex];
      const int a = plan.aIsFirstCondition ? 0 : 1, b = 1 - a;
      trial->reset();
      trial->bind(1, protocol.id)
          .bind(2, participantId)
          .bind(3, int(plan.position))
          .bind(4, structure)
          .bind(5, protocol.conditions[std::size_t(a)].id)
          .bind(6, protocol.conditions[std::size_t(b)].id)
          .bind(7, protocol.presetFor(structure, a))
          .bind(8, protocol.presetFor(structure, b));
      if (auto s = trial->run(); !s) return s;
    }
    return {};
  }, !server);
  if (!written) return tl::unexpected(written.error());
  return loadParticipant(db, protocol.id, participantId);
}

namespace {

// Inside a write transaction: fails unless `participant`'s session is still the latest one.
Status checkSessionCurrent(Database& d, const StudyParticipant& participant) {
  auto st = d.prepare("SELECT session FROM study_participants WHERE study_id = ?1 AND participant_id = ?2");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, participant.studyId).bind(2, participant.participantId);
  auto row = st->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row)
    return fail(ErrorKind::NotFound, "study '" + participant.studyId + "' has no participant '" +
                                         participant.participantId + "'");
  const int latest = st->integer(0);
  if (latest == participant.session) return {};
  return fail(ErrorKind::Conflict,
              "study '" + participant.studyId + "': participant '" + participant.participantId +
                  "' was resumed by another session (session " + std::to_string(latest) + ") after this one (session " +
                  std::to_string(participant.session) +
                  ") began; this session stops here and keeps what it saved — finish in session " +
                  std::to_string(latest) + ", or resume the participant again to take over");
}

}  // namespace

Status recordRating(Database& db, const StudyParticipant& participant, const RatingRecord& rating) {
  const std::string& studyId = participant.studyId;
  const std::string& participantId = participant.participantId;
  return db.keyedWriteTransaction(participantKey(studyId, participantId), [&](Database& d) -> Status {
    if (auto current = checkSessionCurrent(d, participant); !current) return current;
    if (detail::studyWritesThroughServer(d)) return detail::recordRatingOnServer(d, participant, rating);
    auto st = d.prepare(
        "INSERT INTO study_ratings (study_id, participant_id, position, item, rating_ab, response_ms, t, alpha, beta, "
        "app_version, session, created_at, quality_level, quality_full_level, quality_scale, settle_ms) "
        "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, "
        "(SELECT session FROM study_participants WHERE study_id = ?1 AND participant_id = ?2), ?11, ?12, ?13, ?14, ?15) "
        "ON CONFLICT(study_id, participant_id, position, item) DO UPDATE SET rating_ab = excluded.rating_ab, "
        "response_ms = excluded.response_ms, t = excluded.t, alpha = excluded.alpha, beta = excluded.beta, "
        "app_version = excluded.app_version, session = excluded.session, created_at = excluded.created_at, "
        "quality_level = excluded.quality_level, quality_full_level = excluded.quality_full_level, "
        "quality_scale = excluded.quality_scale, settle_ms = excluded.settle_ms");
    if (!st) return tl::unexpected(st.error());
    st->bind(1, studyId)
        .bind(2, participantId)
        .bind(3, rating.position)
        .bind(4, rating.item)
        .bind(5, rating.ratingAsShown)
        .bind(6, rating.responseMs)
        .bind(7, rating.t)
        .bind(8, rating.alpha)
        .bind(9, rating.beta)
        .bind(10, rating.appVersion)
        .bind(11, utcTimestampNow())
        .bind(12, rating.qualityLevel)
        .bind(13, rating.qualityFullLevel)
        .bind(14, rating.qualityScale)
        .bind(15, rating.settleMs);
    return st->run();
  });
}

Status recordTrialViewing(Database& db, const StudyParticipant& participant, int position, double viewMsA,
                          double viewMsB, int toggles, const std::string& comment, bool viewingMeasured) {
  const std::string& studyId = participant.studyId;
  const std::string& participantId = participant.participantId;
  return db.keyedWriteTransaction(participantKey(studyId, participantId), [&](Database& d) -> Status {
    if (auto current = checkSessionCurrent(d, participant); !current) return current;
    if (detail::studyWritesThroughServer(d))
      return detail::recordTrialViewingOnServer(d, participant, position, viewMsA, viewMsB, toggles, comment,
                                                viewingMeasured);
    auto st = d.prepare(
        "UPDATE study_trials SET view_ms_a = ?4, view_ms_b = ?5, toggles = ?6, comment = ?7, viewing_measured = ?8 "
        "WHERE study_id = ?1 AND participant_id = ?2 AND position = ?3");
    if (!st) return tl::unexpected(st.error());
    st->bind(1, studyId).bind(2, participantId).bind(3, position);
    if (viewingMeasured) st->bind(4, viewMsA).bind(5, viewMsB).bind(6, toggles);
    else st->bindNull(4).bindNull(5).bind(6, 0);
    if (comment.empty()) st->bindNull(7);
    else st->bind(7, comment);
    st->bind(8, viewingMeasured ? 1 : 0);
    if (auto s = st->run(); !s) return s;
    if (d.changes() != 1)
      return fail("study '" + studyId + "': participant '" + participantId + "' has no trial " + std::to_string(position));
    return {};
  });
}

Status markParticipantComplete(Database& db, const StudyParticipant& participant) {
  const std::string& studyId = participant.studyId;
  const std::string& participantId = participant.participantId;
  return db.keyedWriteTransaction(participantKey(studyId, participantId), [&](Database& d) -> Status {
    if (auto current = checkSessionCurrent(d, participant); !current) return current;
    if (detail::studyWritesThroughServer(d)) return detail::completeParticipantOnServer(d, participant);
    auto st = d.prepare(
        "UPDATE study_participants SET completed_at = ?3 "
        "WHERE study_id = ?1 AND participant_id = ?2 AND completed_at IS NULL");
    if (!st) return tl::unexpected(st.error());
    st->bind(1, studyId).bind(2, participantId).bind(3, utcTimestampNow());
    return st->run();
  });
}

Result<std::vector<StudyCompletion>> studyCompletion(Database& db, const std::string& studyId) {
  auto study = findStudy(db, studyId);
  if (!study) return tl::unexpected(study.error());
  if (!*study) return fail(ErrorKind::NotFound, "no study '" + studyId + "' in " + db.path());
  auto st = db.prepare(
      "SELECT p.participant_id, p.group_name, CASE WHEN p.completed_at IS NULL THEN 0 ELSE 1 END, "
      " (SELECT count(*) FROM study_ratings r WHERE r.study_id = p.study_id AND r.participant_id = p.participant_id), "
      " p.withdrawal_kind || ': ' || p.withdrawal_reason "
      "FROM study_participants p WHERE p.study_id = ?1 ORDER BY p.enrolment_index");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, studyId);
  std::vector<StudyCompletion> out;
  while (true) {
    auto row = st->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    StudyCompletion c;
    c.participantId = st->text(0);
    c.group = st->text(1);
    c.complete = st->integer(2) != 0;
    c.ratingsGiven = st->integer(3);
    c.ratingsExpected = int((*study)->structures.size() * (*study)->items.size());
    c.withdrawal = st->optionalText(4);
    out.push_back(c);
  }
  return out;
}

Result<std::vector<quiz::StudyParticipantRow>> studyParticipantRows(Database& db, const std::string& studyId) {
  auto st = db.prepare(
      "SELECT participant_id, group_name, enrolment_index, session, CASE WHEN completed_at IS NULL THEN 0 ELSE 1 END "
      "FROM study_participants WHERE study_id = ?1 AND withdrawn_at IS NULL ORDER BY enrolment_index");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, studyId);
  std::vector<quiz::StudyParticipantRow> out;
  while (true) {
    auto row = st->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    quiz::StudyParticipantRow p;
    p.participantId = st->text(0);
    p.group = st->text(1);
    p.enrolmentIndex = st->integer(2);
    p.sessions = st->integer(3);
    p.complete = st->integer(4) != 0;
    out.push_back(p);
  }
  return out;
}

Result<std::vector<quiz::StudyResponseRow>> studyResponseRows(Database& db, const quiz::StudyProtocol& protocol) {
  return detail::responseRows(db, protocol, std::nullopt);
}

namespace detail {

Result<std::vector<quiz::StudyResponseRow>> responseRows(Database& db, const quiz::StudyProtocol& protocol,
                                                         const std::optional<std::string>& participantId) {
  std::map<std::string, int> itemOrder;
  for (std::size_t i = 0; i < protocol.items.size(); ++i) itemOrder[protocol.items[i].id] = int(i);
  auto st = db.prepare(
      "SELECT p.participant_id, p.group_name, r.session, t.structure, r.item, r.rating_ab, t.a_condition, t.position, "
      " t.preset_a, t.preset_b, r.t, r.alpha, r.beta, t.view_ms_a, t.view_ms_b, t.toggles, r.response_ms, "
      " r.created_at, r.app_version, t.comment, CASE WHEN p.completed_at IS NULL THEN 0 ELSE 1 END, "
      " p.enrolment_index, t.viewing_measured, r.quality_level, r.quality_full_level, r.quality_scale, r.settle_ms "
      "FROM study_ratings r "
      "JOIN study_trials t ON t.study_id = r.study_id AND t.participant_id = r.participant_id AND t.position = r.position "
      "JOIN study_participants p ON p.study_id = r.study_id AND p.participant_id = r.participant_id "
      "WHERE r.study_id = ?1" + std::string(participantId ? " AND r.participant_id = ?2" : " AND p.withdrawn_at IS NULL") +
      " ORDER BY p.enrolment_index, t.position");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, protocol.id);
  if (participantId) st->bind(2, *participantId);
  std::vector<std::pair<std::tuple<int, int, int>, quiz::StudyResponseRow>> keyed;
  while (true) {
    auto row = st->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    quiz::StudyResponseRow r;
    r.participantId = st->text(0);
    r.group = st->text(1);
    r.session = st->isNull(2) ? 0 : st->integer(2);
    r.structure = st->text(3);
    r.item = st->text(4);
    r.ratingAb = st->integer(5);
    r.aCondition = st->text(6);
    r.presentationOrder = st->integer(7) + 1;
    r.presetA = st->text(8);
    r.presetB = st->text(9);
    r.t = st->real(10);
    r.alpha = st->real(11);
    r.beta = st->real(12);
    r.viewMsA = st->real(13);
    r.viewMsB = st->real(14);
    r.toggles = st->integer(15);
    r.responseMs = st->real(16);
    // Stored as 2026-11-22T05:01:02.345Z; exported to the second, as ISO 8601 UTC.
    std::string ts = st->text(17);
    if (auto dot = ts.find('.'); dot != std::string::npos) ts = ts.substr(0, dot) + "Z";
    r.timestampUtc = ts;
    r.appVersion = st->text(18);
    r.comment = st->optionalText(19).value_or("");
    r.participantComplete = st->integer(20) != 0;
    r.viewingMeasured = st->integer(22) != 0;
    if (!st->isNull(23)) r.qualityLevel = st->integer(23);
    if (!st->isNull(24)) r.qualityFullLevel = st->integer(24);
    if (!st->isNull(25)) r.qualityScale = st->real(25);
    if (!st->isNull(26)) r.settleMs = st->real(26);
    const bool aIsFirst = r.aCondition == protocol.conditions[0].id;
    r.rating = quiz::unblindRating(r.ratingAb, aIsFirst, protocol.scale);
    auto order = itemOrder.find(r.item);
    keyed.push_back({{st->integer(21), st->integer(7), order == itemOrder.end() ? 1 << 20 : order->second}, r});
  }
  std::stable_sort(keyed.begin(), keyed.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<quiz::StudyResponseRow> rows;
  for (auto& k : keyed) rows.push_back(std::move(k.second));
  return rows;
}

}  // namespace detail

}  // namespace at::db
