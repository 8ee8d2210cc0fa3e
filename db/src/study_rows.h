// What the study store and the study merge share (private to db/).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "database.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"

namespace at::db::detail {

// Fields of a stored study that participants' data depend on: changing them would make recorded
// trials meaningless.
bool sameDesign(const quiz::StudyProtocol& a, const quiz::StudyProtocol& b);
Result<int> participantCount(Database& db, const std::string& studyId);
// Inserts the study's row or updates it in place (inside the caller's transaction).
Status storeStudyRow(Database& db, const quiz::StudyProtocol& protocol);
// studyResponseRows, of one participant when `participantId` is given.
Result<std::vector<quiz::StudyResponseRow>> responseRows(Database& db, const quiz::StudyProtocol& protocol,
                                                         const std::optional<std::string>& participantId);

}  // namespace at::db::detail
