// Preference studies in the database: the protocol, the participants (pseudonymous, with a group
// and an enrolment index that fixes their counterbalancing row), one trial per participant ×
// structure with its blinded A/B mapping, and every rating as it is given (one transaction each).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "db/connection.h"
#include "quiz/redcap_export.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"

namespace at::db {

struct StudyTrial {
  int position = 0;                 // 0-based presentation order
  std::string structure;
  std::string aCondition, bCondition;  // condition ids shown as A and B
  std::string presetA, presetB;
  double viewMsA = 0, viewMsB = 0;
  int toggles = 0;
  bool viewingMeasured = true;      // false: shown as files outside the program, times not known
  std::string comment;
  std::set<std::string> ratedItems;
};

struct StudyParticipant {
  std::string studyId;
  std::string participantId;
  std::string group;
  int enrolmentIndex = 0;           // 0-based order of enrolment: the counterbalancing row
  int session = 1;                  // how many times the participant has started (resumes count)
  bool complete = false;
  std::vector<StudyTrial> trials;   // in presentation order

  // The first trial with an unrated item, or nullopt when every item of every trial is rated.
  std::optional<std::size_t> nextTrial(std::size_t itemCount) const;
};

struct StudyCompletion {
  std::string participantId, group;
  int ratingsGiven = 0, ratingsExpected = 0;
  bool complete = false;
  std::optional<std::string> withdrawal;  // "withdrawn: <reason>" or "excluded: <reason>" (db/study_withdrawal.h)
};

// On a class server every write below goes through the server's audited functions
// (db/src/study_writes_sql.cpp): a coordinator's login registers a study (it becomes hers) and
// alone records its participants; any other login is refused and nothing changes.
//
// Stores (or updates) a study definition. A study that already has participants may only be
// re-stored unchanged in its structures, conditions, items and seed (an error names the study).
Status saveStudy(Database& db, const quiz::StudyProtocol& protocol);
Result<std::optional<quiz::StudyProtocol>> findStudy(Database& db, const std::string& studyId);
Result<std::vector<quiz::StudyProtocol>> listStudies(Database& db);

// Participant ids: quiz::validParticipantId (pseudonyms that are valid REDCap record names).
using quiz::validParticipantId;

// Enrols a participant (plan from the Latin square row of their enrolment index and the study's
// seed) or resumes one already enrolled (group must match; the session count goes up).
Result<StudyParticipant> enrolOrResume(Database& db, const quiz::StudyProtocol& protocol,
                                       const std::string& participantId, const std::string& group);

struct RatingRecord {
  int position = 0;
  std::string item;
  int ratingAsShown = 0;            // 1 = prefer A … 5 = prefer B
  double responseMs = 0;
  double t = 0, alpha = 0, beta = 0;  // render parameters on screen
  std::string appVersion;
  // The render quality on screen when the item was rated: the level (qualityFullLevel = full),
  // the full level's resolution as a share of the view, and ms from the rated side being shown
  // to the full level on screen. Unset: not known (no view drew the trial).
  std::optional<int> qualityLevel, qualityFullLevel;
  std::optional<double> qualityScale, settleMs;
};
// The writes of one participant's session (`participant` as enrolOrResume returned it). Only the
// participant's latest session may write: once another run resumes the same participant (its
// session number is higher), each write of the earlier one is refused with a Conflict naming both
// sessions, so two runs never interleave or overwrite each other's ratings.
//
// Records one rating at once (its own transaction), with the participant's session. Re-rating the
// same item replaces it.
Status recordRating(Database& db, const StudyParticipant& participant, const RatingRecord& rating);
// Records viewing time, toggles and comment of a trial (replacing earlier values). With
// `viewingMeasured` false the times and toggles are not known (the views were shown as files) and
// are stored blank (NULL; toggles 0), read back as 0 with viewingMeasured false, and exported blank.
Status recordTrialViewing(Database& db, const StudyParticipant& participant, int position, double viewMsA,
                          double viewMsB, int toggles, const std::string& comment, bool viewingMeasured = true);
Status markParticipantComplete(Database& db, const StudyParticipant& participant);

Result<std::vector<StudyCompletion>> studyCompletion(Database& db, const std::string& studyId);

// Every enrolled participant in enrolment order (the records of a REDCap export).
Result<std::vector<quiz::StudyParticipantRow>> studyParticipantRows(Database& db, const std::string& studyId);

// Every rating as an export row, unblinded, ordered by enrolment, position, item order.
Result<std::vector<quiz::StudyResponseRow>> studyResponseRows(Database& db, const quiz::StudyProtocol& protocol);

// Combining a study run on machines that had no class server: every participant of every source
// (participant, trials and ratings as recorded: sessions, times, comments) is copied into `into`,
// all sources in one transaction. A participant already in `into` (or in an earlier source) with
// exactly the same records is left as it is, so merging again changes nothing; the same id with
// other records is a Conflict naming both places, and nothing is written. The study must be in
// every database source with one design (structures, conditions, items, scale, seed); `into` gets
// it when it has none. Merged participants are enrolled after those already in `into`; their
// trials keep the counterbalancing row their machine gave them, which the report lists.
//
// A source may instead be an export bundle's long table (quiz::readResponsesLongCsv, read against
// `design`, which must then be given). It holds what the export holds: the rated trials, times to
// the ms, timestamps to the second (stored as .000), started_at/completed_at as the first and last
// rating. Such a participant counts as already there when the long table `into` would export for
// them is the bundle's, whichever way their records came; a database participant whose records
// differ from the stored ones is compared that way too (a bundle and the database it came from
// agree).
struct StudyMergeSource {
  std::string name;  // for messages: the file, server or bundle folder
  Database* db = nullptr;
  const std::vector<quiz::StudyResponseRow>* rows = nullptr;  // a bundle's long table when db is null
};
struct StudyMergeReport {
  struct FromSource {
    std::string name;
    int added = 0, alreadyThere = 0;
    int withdrawals = 0;  // withdrawals and exclusions carried into `into` (its own stay as they are)
  };
  std::vector<FromSource> sources;
  int participants = 0;                     // in `into` after the merge
  std::size_t cycle = 0;                    // design rows in one full counterbalancing cycle
  std::map<std::size_t, int> designRows;    // design row → participants whose trials follow it
  std::vector<std::string> offDesign;       // participants whose trials follow no row of the design
  // Every row of the cycle used equally often, give or take one (as enrolling on one machine does).
  // A bundle's partial participant counts for the first row their rated trials agree with.
  bool balanced() const;
};
// `design`: the study as the bundles were read (required when a source is a bundle); database
// sources must agree with it.
Result<StudyMergeReport> mergeStudy(Database& into, const std::vector<StudyMergeSource>& sources,
                                    const std::string& studyId, const quiz::StudyProtocol* design = nullptr);

}  // namespace at::db
