// What the study store and the study merge share (private to db/).
#pragma once

#include <string>

#include "database.h"
#include "quiz/study_protocol.h"

namespace at::db::detail {

// Fields of a stored study that participants' data depend on: changing them would make recorded
// trials meaningless.
bool sameDesign(const quiz::StudyProtocol& a, const quiz::StudyProtocol& b);
Result<int> participantCount(Database& db, const std::string& studyId);
// Inserts the study's row or updates it in place (inside the caller's transaction).
Status storeStudyRow(Database& db, const quiz::StudyProtocol& protocol);

}  // namespace at::db::detail
