// What the learning commands (play, progress, courses, lessons) share: the database opened with
// the default course seeded, the structures of the built-in dataset, a course's dataset loaded
// for key computation, and a KeyComputer whose distances come from computeWdt.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "db/database.h"
#include "db/sqlite_repositories.h"
#include "quiz/keys.h"
#include "core/error.h"
#include "volume/structure.h"

namespace at::app {

// The course folder: $AT_DATA_DIR/courses when set, else the source tree's data/courses.
std::string courseDirectory();

// Opens `--db PATH` (or the default database) and seeds the courses of courseDirectory()
// (idempotent: a course already stored at the same version is left as it is). With `readOnly`
// (commands that only read), a database this process cannot write is opened read-only and not
// seeded.
Result<db::Database> openLearningDatabase(const std::optional<std::string>& dbPath, bool readOnly = false);

// The built-in datasets' structures without building their volumes ("phantom", "phantom:N").
db::BuiltinStructures builtinStructures();

// Loads a course's dataset: a built-in one by name, else an imported one from the database.
Result<Dataset> loadCourseDataset(db::Database& db, const std::string& datasetId);

// Distance fields for key computation: the weighted distance transform (density weights, the
// paper's entering rule, sweeps until converged) from a structure's voxels, computed on a grid
// coarser by 2 per axis (as the paper does for interaction: 8x fewer voxels) and sampled back
// trilinearly onto the label grid. Keys compare distances between structures millimetres apart,
// and a relation key must win by kRelationMargin, so the coarser grid does not change them.
quiz::DistanceFieldFunction wdtDistanceField(const Dataset& dataset);

// A KeyComputer that answers hasStructure from a structure list and loads the dataset (and computes
// distance fields) only when a key needs it: lessons without relation, order or computed identify
// questions start without building a volume.
class LazyKeyComputer final : public quiz::KeyComputer {
 public:
  using Loader = std::function<Result<Dataset>()>;
  LazyKeyComputer(std::vector<Structure> structures, Loader loader);
  bool hasStructure(const std::string& structureId) const override;
  Result<quiz::StructureDistances> distancesFrom(const std::string& structureId) override;
  Result<Vec3> centroidMm(const std::string& structureId) override;
  Result<std::vector<std::string>> structuresAlong(const Vec3& entryMm, const Vec3& targetMm) override;

 private:
  Result<quiz::KeyComputer*> loaded();
  std::vector<Structure> structures_;
  Loader loader_;
  std::unique_ptr<Dataset> dataset_;
  std::unique_ptr<quiz::DatasetKeyComputer> keys_;
};

}  // namespace at::app
