// Reading an export bundle's long table (responses_long.csv, as responsesLongCsv writes it) back,
// so that `study merge` can combine the bundles of lab machines that share no database.
#pragma once

#include <string>
#include <vector>

#include "core/error.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"

namespace at::quiz {

// Parses `text` strictly as the long table of `protocol`'s study and returns its rows in file
// order. Accepted: RFC 4180 records ended by CRLF or LF, an optional UTF-8 byte order mark, the
// header of this version or of exports written before the four quality columns were added. Every
// value is checked: participant ids as validParticipantId, groups, structures, items and
// conditions of the study, ratings on its scale with `rating` the unblinded `rating_ab`, numbers
// finite (times not negative), timestamps ISO 8601 UTC to the second, viewing times and toggles
// all present or all blank; and across rows: one group and completion per participant, one
// presentation order, blinding, presets, viewing and comment per participant × structure, no
// participant × structure × item twice. Text cells lose the apostrophe csvCell puts before a
// leading '=', '+', '-', '@', TAB or CR. Errors are one printable line naming `source`, the row
// (the header is row 1) and the column: "responses_long.csv: row 7, column 'rating': 6 is not on
// the study's scale 1–5".
Result<std::vector<StudyResponseRow>> readResponsesLongCsv(const std::string& text, const std::string& source,
                                                           const StudyProtocol& protocol);

}  // namespace at::quiz
