// `mergeStudy`: a study's participants from several databases (lab machines without a class
// server) copied into one, row by row with every recorded column, in one transaction.
#include <algorithm>
#include <map>
#include <set>
#include <type_traits>

#include <nlohmann/json.hpp>

#include "db/study_store.h"
#include "quiz/study_design.h"
#include "server_refusal.h"
#include "study_rows.h"
#include "study_server_writes.h"

namespace at::db {

namespace {

enum class Type { Int, Real, Text };
struct Column {
  const char* name;
  Type type;
};

// One stored value; two cells are equal when type, nullness and value agree.
struct Cell {
  bool null = false;
  std::int64_t integer = 0;
  double real = 0;
  std::string text;
  bool operator==(const Cell&) const = default;
};
using Row = std::vector<Cell>;

// The columns of a participant's records, besides study_id and participant_id. The enrolment
// index is the participant's place in the target, not part of what they recorded: it is left out
// of the comparison and given anew.
const std::vector<Column> kParticipantColumns = {
    {"group_name", Type::Text}, {"session", Type::Int}, {"started_at", Type::Text}, {"completed_at", Type::Text}};
const std::vector<Column> kTrialColumns = {
    {"position", Type::Int},   {"structure", Type::Text},  {"a_condition", Type::Text}, {"b_condition", Type::Text},
    {"preset_a", Type::Text},  {"preset_b", Type::Text},   {"view_ms_a", Type::Real},   {"view_ms_b", Type::Real},
    {"toggles", Type::Int},    {"comment", Type::Text},    {"viewing_measured", Type::Int}};
const std::vector<Column> kRatingColumns = {
    {"position", Type::Int}, {"item", Type::Text},      {"rating_ab", Type::Int},   {"response_ms", Type::Real},
    {"t", Type::Real},       {"alpha", Type::Real},     {"beta", Type::Real},       {"app_version", Type::Text},
    {"created_at", Type::Text}, {"session", Type::Int},
    {"quality_level", Type::Int}, {"quality_full_level", Type::Int}, {"quality_scale", Type::Real},
    {"settle_ms", Type::Real}};

std::string columnList(const std::vector<Column>& columns) {
  std::string out;
  for (const Column& c : columns) out += (out.empty() ? "" : ", ") + std::string(c.name);
  return out;
}

// Rows of `table` for one participant, ordered by its first column.
Result<std::vector<Row>> readRows(Database& db, const char* table, const std::vector<Column>& columns,
                                  const std::string& studyId, const std::string& participantId) {
  auto st = db.prepare("SELECT " + columnList(columns) + " FROM " + table +
                       " WHERE study_id = ?1 AND participant_id = ?2 ORDER BY " + columnList(columns));
  if (!st) return tl::unexpected(st.error());
  st->bind(1, studyId).bind(2, participantId);
  std::vector<Row> rows;
  while (true) {
    auto more = st->step();
    if (!more) return tl::unexpected(more.error());
    if (!*more) break;
    Row row(columns.size());
    for (std::size_t i = 0; i < columns.size(); ++i) {
      const int at = int(i);
      row[i].null = st->isNull(at);
      if (row[i].null) continue;
      switch (columns[i].type) {
        case Type::Int: row[i].integer = st->int64(at); break;
        case Type::Real: row[i].real = st->real(at); break;
        case Type::Text: row[i].text = st->text(at); break;
      }
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

Status insertRow(Database& db, const char* table, const std::vector<Column>& columns, const std::string& studyId,
                 const std::string& participantId, const Row& row, std::optional<int> enrolmentIndex = std::nullopt) {
  std::string names = "study_id, participant_id, " + columnList(columns), values = "?1, ?2";
  for (std::size_t i = 0; i < columns.size(); ++i) values += ", ?" + std::to_string(i + 3);
  if (enrolmentIndex) {
    names += ", enrolment_index";
    values += ", ?" + std::to_string(columns.size() + 3);
  }
  auto st = db.prepare(std::string("INSERT INTO ") + table + " (" + names + ") VALUES (" + values + ")");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, studyId).bind(2, participantId);
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const int at = int(i) + 3;
    if (row[i].null) st->bindNull(at);
    else if (columns[i].type == Type::Int) st->bind(at, row[i].integer);
    else if (columns[i].type == Type::Real) st->bind(at, row[i].real);
    else st->bind(at, row[i].text);
  }
  if (enrolmentIndex) st->bind(int(columns.size()) + 3, *enrolmentIndex);
  return st->run();
}

// One row as a JSON object {column: value} (nulls as null).
nlohmann::json rowJson(const std::vector<Column>& columns, const Row& row) {
  nlohmann::json out = nlohmann::json::object();
  for (std::size_t i = 0; i < columns.size(); ++i) {
    const Cell& c = row[i];
    if (c.null) out[columns[i].name] = nullptr;
    else if (columns[i].type == Type::Int) out[columns[i].name] = c.integer;
    else if (columns[i].type == Type::Real) out[columns[i].name] = c.real;
    else out[columns[i].name] = c.text;
  }
  return out;
}

// Everything one participant recorded.
struct Records {
  std::string id;
  Row participant;
  std::vector<Row> trials, ratings;
  bool operator==(const Records&) const = default;
};

// A participant's withdrawal or exclusion as a source recorded it.
struct Withdrawal {
  std::string at, kind, reason;
};

// The withdrawn and excluded participants of `studyId` in `db`.
Result<std::map<std::string, Withdrawal>> readWithdrawals(Database& db, const std::string& studyId) {
  std::map<std::string, Withdrawal> out;
  auto s = db.prepare("SELECT participant_id, withdrawn_at, coalesce(withdrawal_kind, 'withdrawn'),"
                      " coalesce(withdrawal_reason, '') FROM study_participants WHERE study_id = ?1 AND withdrawn_at IS NOT NULL");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, studyId);
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    out[r.text(0)] = Withdrawal{r.text(1), r.text(2), r.text(3)};
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

// Carries a source's withdrawal into `d`: a participant withdrawn anywhere stays withdrawn (the
// target's own withdrawal, when it has one, is kept). Returns whether it changed the target. On a
// class server it goes through at_withdraw_participant (the study's current coordinator, audited;
// the withdrawal is dated when it is carried).
Result<bool> carryWithdrawal(Database& d, const std::string& studyId, const std::string& participantId,
                             const Withdrawal& w) {
  if (detail::studyWritesThroughServer(d)) {
    auto current = d.prepare("SELECT 1 FROM study_participants WHERE study_id = ?1 AND participant_id = ?2"
                             " AND withdrawn_at IS NULL");
    if (!current) return tl::unexpected(current.error());
    current->bind(1, studyId).bind(2, participantId);
    auto row = current->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return false;
    auto call = d.prepare("SELECT at_withdraw_participant(?1, ?2, ?3, ?4, '')");
    if (!call) return tl::unexpected(call.error());
    call->bind(1, studyId).bind(2, participantId).bind(3, w.kind).bind(4, w.reason);
    if (auto done = call->step(); !done) return tl::unexpected(serverRefusal(done.error()));
    return true;
  }
  auto s = d.prepare("UPDATE study_participants SET withdrawn_at = ?3, withdrawal_kind = ?4, withdrawal_reason = ?5"
                     " WHERE study_id = ?1 AND participant_id = ?2 AND withdrawn_at IS NULL");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, studyId).bind(2, participantId).bind(3, w.at).bind(4, w.kind).bind(5, w.reason);
  if (auto done = s->step(); !done) return tl::unexpected(done.error());
  return d.changes() > 0;
}

Result<std::optional<Records>> readRecords(Database& db, const std::string& studyId, const std::string& participantId) {
  auto participant = readRows(db, "study_participants", kParticipantColumns, studyId, participantId);
  if (!participant) return tl::unexpected(participant.error());
  if (participant->empty()) return std::optional<Records>{};
  Records r{participantId, participant->front(), {}, {}};
  auto trials = readRows(db, "study_trials", kTrialColumns, studyId, participantId);
  if (!trials) return tl::unexpected(trials.error());
  auto ratings = readRows(db, "study_ratings", kRatingColumns, studyId, participantId);
  if (!ratings) return tl::unexpected(ratings.error());
  r.trials = std::move(*trials);
  r.ratings = std::move(*ratings);
  return std::optional<Records>{std::move(r)};
}

Result<std::vector<Records>> readAllRecords(Database& db, const std::string& studyId) {
  auto ids = db.prepare("SELECT participant_id FROM study_participants WHERE study_id = ?1 ORDER BY enrolment_index");
  if (!ids) return tl::unexpected(ids.error());
  ids->bind(1, studyId);
  std::vector<std::string> names;
  while (true) {
    auto more = ids->step();
    if (!more) return tl::unexpected(more.error());
    if (!*more) break;
    names.push_back(ids->text(0));
  }
  std::vector<Records> out;
  for (const auto& id : names) {
    auto records = readRecords(db, studyId, id);
    if (!records) return tl::unexpected(records.error());
    if (*records) out.push_back(std::move(**records));
  }
  return out;
}

// The first design row a participant's trials follow (position, structure, condition shown as A),
// if any. A database participant has every trial of their plan; a bundle's has the rated ones.
std::optional<std::size_t> designRowOf(const quiz::StudyProtocol& protocol, const std::vector<Row>& trials) {
  const std::size_t cycle = quiz::counterbalancingCycle(protocol.structures.size());
  if (trials.empty()) return std::nullopt;
  for (std::size_t row = 0; row < cycle; ++row) {
    std::map<std::int64_t, quiz::TrialPlan> byPosition;
    for (const auto& planned : quiz::planParticipant(protocol.structures.size(), row, protocol.seed))
      byPosition[std::int64_t(planned.position)] = planned;
    bool same = trials.size() <= byPosition.size();
    for (std::size_t i = 0; same && i < trials.size(); ++i) {
      const Row& t = trials[i];
      const auto planned = byPosition.find(t[0].integer);
      same = planned != byPosition.end() && t[1].text == protocol.structures[planned->second.structureIndex] &&
             t[2].text == protocol.conditions[planned->second.aIsFirstCondition ? 0 : 1].id;
    }
    if (same) return row;
  }
  return std::nullopt;
}

// The long table's records of some rows, sorted: what an export shows of a participant, in any order.
std::vector<std::string> exportLines(const std::vector<quiz::StudyResponseRow>& rows) {
  std::vector<std::string> lines;
  for (const auto& row : rows) lines.push_back(quiz::responsesLongCsv({row}));
  std::sort(lines.begin(), lines.end());
  return lines;
}

Result<std::vector<std::string>> exportLinesOf(Database& db, const quiz::StudyProtocol& design,
                                               const std::string& participantId) {
  auto rows = detail::responseRows(db, design, participantId);
  if (!rows) return tl::unexpected(rows.error());
  return exportLines(*rows);
}

Cell textCell(std::string text) { return Cell{false, 0, 0, std::move(text)}; }
Cell intCell(std::int64_t value) { return Cell{false, value, 0, {}}; }
Cell realCell(double value) { return Cell{false, 0, value, {}}; }
Cell nullCell() { return Cell{true, 0, 0, {}}; }
template <class T>
Cell optionalCell(const std::optional<T>& value) {
  if (!value) return nullCell();
  if constexpr (std::is_integral_v<T>) return intCell(*value);
  else return realCell(*value);
}

// A bundle's rows as records in the stored layout (participants in the order they first appear).
// Timestamps exported to the second are stored with .000 milliseconds.
std::vector<Records> recordsFromRows(const quiz::StudyProtocol& design, const std::vector<quiz::StudyResponseRow>& rows) {
  std::vector<Records> out;
  std::map<std::string, std::size_t> at;
  std::map<std::string, std::set<std::int64_t>> trialsOf;
  std::map<std::string, std::pair<std::string, std::string>> firstLast;  // participant → first, last rating time
  for (const auto& r : rows) {
    auto [it, isNew] = at.try_emplace(r.participantId, out.size());
    if (isNew) out.push_back(Records{r.participantId, {}, {}, {}});
    Records& records = out[it->second];
    const std::string stored = r.timestampUtc.substr(0, r.timestampUtc.size() - 1) + ".000Z";
    auto [times, firstTime] = firstLast.try_emplace(r.participantId, stored, stored);
    if (!firstTime) {
      times->second.first = std::min(times->second.first, stored);
      times->second.second = std::max(times->second.second, stored);
    }
    const std::int64_t position = r.presentationOrder - 1;
    if (trialsOf[r.participantId].insert(position).second) {
      const std::string& b = design.conditions[r.aCondition == design.conditions[0].id ? 1 : 0].id;
      records.trials.push_back({intCell(position), textCell(r.structure), textCell(r.aCondition), textCell(b),
                                textCell(r.presetA), textCell(r.presetB), realCell(r.viewMsA), realCell(r.viewMsB),
                                intCell(r.toggles), r.comment.empty() ? nullCell() : textCell(r.comment),
                                intCell(r.viewingMeasured ? 1 : 0)});
    }
    records.ratings.push_back({intCell(position), textCell(r.item), intCell(r.ratingAb), realCell(r.responseMs),
                               realCell(r.t), realCell(r.alpha), realCell(r.beta), textCell(r.appVersion),
                               textCell(stored), r.session > 0 ? intCell(r.session) : nullCell(),
                               optionalCell(r.qualityLevel), optionalCell(r.qualityFullLevel),
                               optionalCell(r.qualityScale), optionalCell(r.settleMs)});
    // The participant's session count: the latest session any rating names (1 when none does).
    const std::int64_t session = std::max<std::int64_t>(1, r.session);
    if (records.participant.empty())
      records.participant = {textCell(r.group), intCell(session), nullCell(), nullCell()};
    records.participant[1].integer = std::max(records.participant[1].integer, session);
    records.participant[2] = textCell(times->second.first);
    records.participant[3] = r.participantComplete ? textCell(times->second.second) : nullCell();
  }
  return out;
}

// Everything one source holds of the study; `lines` (bundles only): each participant's export lines.
struct SourceRecords {
  std::vector<Records> records;
  std::map<std::string, std::vector<std::string>> lines;
};

}  // namespace

bool StudyMergeReport::balanced() const {
  if (cycle == 0 || !offDesign.empty()) return false;
  int least = participants, most = 0;
  for (std::size_t row = 0; row < cycle; ++row) {
    const auto it = designRows.find(row);
    const int used = it == designRows.end() ? 0 : it->second;
    least = std::min(least, used);
    most = std::max(most, used);
  }
  return most - least <= 1;
}

Result<StudyMergeReport> mergeStudy(Database& into, const std::vector<StudyMergeSource>& sources,
                                    const std::string& studyId, const quiz::StudyProtocol* givenDesign) {
  // Read every source first: the sources are other databases, outside the target's transaction.
  std::optional<quiz::StudyProtocol> design;
  std::string designFrom = "the study given";
  if (givenDesign) {
    if (givenDesign->id != studyId)
      return fail(ErrorKind::Conflict, "study merge: the study given is '" + givenDesign->id + "', not '" + studyId + "'");
    design = *givenDesign;
  }
  std::vector<SourceRecords> fromSources;
  std::vector<std::map<std::string, Withdrawal>> withdrawals;  // per source (a bundle has none: it leaves them out)
  for (const auto& source : sources) {
    withdrawals.emplace_back();
    if (!source.db) {
      if (!source.rows || !givenDesign)
        return fail(source.name + ": an export bundle is merged against the study's design, which was not given");
      SourceRecords bundle{recordsFromRows(*design, *source.rows), {}};
      std::map<std::string, std::vector<quiz::StudyResponseRow>> byParticipant;
      for (const auto& row : *source.rows) byParticipant[row.participantId].push_back(row);
      for (const auto& [id, rows] : byParticipant) bundle.lines[id] = exportLines(rows);
      fromSources.push_back(std::move(bundle));
      continue;
    }
    auto study = findStudy(*source.db, studyId);
    if (!study) return tl::unexpected(withContext(source.name, study.error()));
    if (!*study) return fail(ErrorKind::NotFound, source.name + ": has no study '" + studyId + "'");
    if (design && !detail::sameDesign(*design, **study))
      return fail(ErrorKind::Conflict, source.name + ": study '" + studyId +
                                           "' has another design (structures, conditions, items, scale or seed) than " +
                                           designFrom);
    if (!design) {
      design = **study;
      designFrom = "in " + source.name;
    }
    auto records = readAllRecords(*source.db, studyId);
    if (!records) return tl::unexpected(withContext(source.name, records.error()));
    auto withdrawn = readWithdrawals(*source.db, studyId);
    if (!withdrawn) return tl::unexpected(withContext(source.name, withdrawn.error()));
    withdrawals.back() = std::move(*withdrawn);
    fromSources.push_back(SourceRecords{std::move(*records), {}});
  }
  if (!design) return fail("study merge: no databases to merge from");

  StudyMergeReport report;
  auto written = into.writeTransaction([&](Database& d) -> Status {
    report.sources.clear();
    auto target = findStudy(d, studyId);
    if (!target) return tl::unexpected(target.error());
    if (*target && !detail::sameDesign(**target, *design))
      return fail(ErrorKind::Conflict, d.path() + ": study '" + studyId + "' has another design than " +
                                           designFrom + "; nothing was merged");
    // On a class server every write goes through its checked, audited functions.
    const bool viaServer = detail::studyWritesThroughServer(d);
    if (!*target) {
      if (auto s = viaServer ? detail::registerStudyOnServer(d, *design, "") : detail::storeStudyRow(d, *design); !s)
        return s;
    }
    auto count = detail::participantCount(d, studyId);
    if (!count) return tl::unexpected(count.error());
    int next = *count;
    std::map<std::string, std::string> origin;  // participant → where the target's copy came from
    for (std::size_t s = 0; s < sources.size(); ++s) {
      StudyMergeReport::FromSource from{sources[s].name, 0, 0, 0};
      const SourceRecords& source = fromSources[s];
      const auto carry = [&](const std::string& participantId) -> Status {
        const auto w = withdrawals[s].find(participantId);
        if (w == withdrawals[s].end()) return {};
        auto changed = carryWithdrawal(d, studyId, participantId, w->second);
        if (!changed) return tl::unexpected(changed.error());
        from.withdrawals += *changed ? 1 : 0;
        return {};
      };
      for (const Records& records : source.records) {
        auto existing = readRecords(d, studyId, records.id);
        if (!existing) return tl::unexpected(existing.error());
        if (*existing) {
          bool same = !sources[s].rows && **existing == records;
          if (!same) {  // the same export: a bundle, or a database and a bundle of it
            auto stored = exportLinesOf(d, *design, records.id);
            if (!stored) return tl::unexpected(stored.error());
            const auto bundled = source.lines.find(records.id);
            if (bundled != source.lines.end()) {
              same = *stored == bundled->second;
            } else {
              auto theirs = exportLinesOf(*sources[s].db, *design, records.id);
              if (!theirs) return tl::unexpected(withContext(sources[s].name, theirs.error()));
              same = *stored == *theirs;
            }
          }
          if (same) {
            ++from.alreadyThere;
            if (auto st = carry(records.id); !st) return st;
            continue;
          }
          const auto o = origin.find(records.id);
          return fail(ErrorKind::Conflict,
                      "participant '" + records.id + "' of " + sources[s].name + " is also in " +
                          (o == origin.end() ? d.path() : o->second) +
                          " with other records (two people with one id, or one person run twice); nothing was merged: "
                          "decide which to keep and merge the others");
        }
        origin[records.id] = sources[s].name;
        ++from.added;
        if (viaServer) {  // checked and audited by the server (study_checks_sql.cpp), withdrawal included
          nlohmann::json all = {{"participant", rowJson(kParticipantColumns, records.participant)},
                                {"trials", nlohmann::json::array()}, {"ratings", nlohmann::json::array()}};
          for (const Row& t : records.trials) all["trials"].push_back(rowJson(kTrialColumns, t));
          for (const Row& r : records.ratings) all["ratings"].push_back(rowJson(kRatingColumns, r));
          if (const auto w = withdrawals[s].find(records.id); w != withdrawals[s].end()) {
            all["participant"]["withdrawn_at"] = w->second.at;
            all["participant"]["withdrawal_kind"] = w->second.kind;
            all["participant"]["withdrawal_reason"] = w->second.reason;
            ++from.withdrawals;
          }
          auto call = d.prepare("SELECT at_merge_participant(?1, ?2, ?3, ?4)");
          if (!call) return tl::unexpected(call.error());
          call->bind(1, studyId).bind(2, records.id).bind(3, all.dump()).bind(4, sources[s].name);
          if (auto done = call->step(); !done) return tl::unexpected(serverRefusal(done.error()));
          continue;
        }
        if (auto st = insertRow(d, "study_participants", kParticipantColumns, studyId, records.id, records.participant,
                                next++);
            !st)
          return st;
        for (const Row& t : records.trials)
          if (auto st = insertRow(d, "study_trials", kTrialColumns, studyId, records.id, t); !st) return st;
        for (const Row& r : records.ratings)
          if (auto st = insertRow(d, "study_ratings", kRatingColumns, studyId, records.id, r); !st) return st;
        if (auto st = carry(records.id); !st) return st;
      }
      report.sources.push_back(from);
    }
    return {};
  });
  if (!written) return tl::unexpected(written.error());

  auto merged = readAllRecords(into, studyId);
  if (!merged) return tl::unexpected(merged.error());
  report.participants = int(merged->size());
  report.cycle = quiz::counterbalancingCycle(design->structures.size());
  for (const Records& r : *merged) {
    if (auto row = designRowOf(*design, r.trials)) ++report.designRows[*row];
    else report.offDesign.push_back(r.id);
  }
  return report;
}

}  // namespace at::db
