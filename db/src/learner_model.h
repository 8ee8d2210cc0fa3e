// The learner-model half of recording an answer, shared by the lesson, review and exam
// repositories (private to db/src): run inside the caller's write transaction.
#pragma once

#include <cstdint>

#include "database.h"
#include "lessons/repositories.h"

namespace at::db {

// Writes the structure's memory state, its review-log entry (`source`, `sourceId`: the answer's
// row), the user's ability and the question's difficulty.
Status writeLearnerModel(Database& d, const lessons::LearnerUpdate& update, const lessons::GradedAnswer& answer,
                         lessons::AnswerSource source, std::int64_t sourceId);

}  // namespace at::db
