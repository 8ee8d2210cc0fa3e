// What the learning commands (play, progress, courses, lessons) share: the database opened with
// the default course seeded, the structures of the built-in dataset, a course's dataset loaded
// for key computation, and a KeyComputer whose distances come from computeWdt.
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "db/database.h"
#include "db/sqlite_repositories.h"
#include "quiz/keys.h"
#include "volume/error.h"
#include "volume/structure.h"

namespace at::app {

// The course folder: $AT_DATA_DIR/courses when set, else the source tree's data/courses.
std::string courseDirectory();

// Opens `--db PATH` (or the default database) and seeds the courses of courseDirectory()
// (idempotent: a course already stored at the same version is left as it is).
Result<db::Database> openLearningDatabase(const std::optional<std::string>& dbPath);

// The built-in datasets' structures without building their volumes ("phantom", "phantom:N").
db::BuiltinStructures builtinStructures();

// Loads a course's dataset: a built-in one by name, else an imported one from the database.
Result<Dataset> loadCourseDataset(db::Database& db, const std::string& datasetId);

// Distance fields for key computation: the weighted distance transform (density weights, the
// paper's entering rule, sweeps until converged) from a structure's voxels, on the label grid.
quiz::DistanceFieldFunction wdtDistanceField(const Dataset& dataset);

}  // namespace at::app
