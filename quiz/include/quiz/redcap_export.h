// A preference study as a REDCap project: a data dictionary, the records to import, and the
// repeating-instrument setting, written so that REDCap's Data Dictionary upload and Data Import
// Tool take them without edits.
//
// Layout (REDCap's "repeating instruments" design, a classic non-longitudinal project):
//   record       = one participant; its record id field `participant_id` comes first
//   `participant`       (not repeating): group, enrolment index, sessions, finished flag
//   `structure_rating`  (repeating): one instance per structure × item rated, with the blinded
//                       A/B mapping, both ratings, the render parameters and the viewing data
// The records file has one row per participant (repeat columns blank) and one row per rating
// (`redcap_repeat_instrument` = structure_rating, `redcap_repeat_instance` = 1, 2, …); each row
// fills only its own instrument's fields. Categorical fields hold the codes of their choices
// (1, 2, … in protocol order; ratings hold the scale value); dates are `YYYY-MM-DD HH:MM:SS`
// (validation datetime_seconds_ymd); field names are lowercase letters, digits and underscores,
// start with a letter and stay within 26 characters (REDCap's recommendation).
//
// The repeating setting is not part of a data dictionary: upload `redcap_repeating_forms.csv`
// under Project Setup → "Repeating instruments and events" (or tick `structure_rating` by hand)
// before importing the records.
#pragma once

#include <string>
#include <vector>

#include "quiz/study_protocol.h"
#include "quiz/study_report.h"

namespace at::quiz {

inline constexpr const char* kRedcapParticipantForm = "participant";
inline constexpr const char* kRedcapRatingForm = "structure_rating";

// One enrolled participant (participants who rated nothing yet still get a record).
struct StudyParticipantRow {
  std::string participantId;
  std::string group;
  int enrolmentIndex = 0;   // 0-based counterbalancing row
  int sessions = 1;         // sessions started
  bool complete = false;    // finished every structure
};

std::string redcapDictionaryCsv(const StudyProtocol& protocol);
// `rows` as studyResponseRows gives them (by enrolment, position, item); a participant without
// rows gets its participant row only. Rows of participants not in `participants` are an error
// of the caller (asserted).
std::string redcapRecordsCsv(const StudyProtocol& protocol, const std::vector<StudyParticipantRow>& participants,
                             const std::vector<StudyResponseRow>& rows);
// REDCap's repeating-instruments upload (classic project): form_name,custom_form_label.
std::string redcapRepeatingFormsCsv();

}  // namespace at::quiz
