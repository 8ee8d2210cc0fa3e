// Answer keys computed from the dataset, never written by hand (ARCHITECTURE.md §5):
//   relation — from weighted distances of candidate structures from a structure;
//   order    — by marching the label volume along a straight drilling path;
//   identify — distractors are the target's neighbours: reachable structures nearest it in space.
// The functions take plain inputs; `KeyComputer` supplies them for one dataset, and
// `DatasetKeyComputer` implements it over a Dataset with a caller-supplied WDT (the app passes
// computeWdt; quiz/ itself does not link the WDT library).
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "quiz/question.h"
#include "core/error.h"
#include "volume/structure.h"

namespace at::quiz {

// Weighted distance in mm from one structure to each structure of the dataset: the minimum of
// the source's distance field over the other structure's voxels (+infinity if unreachable).
using StructureDistances = std::map<std::string, double>;

// A nearest key must beat the runner-up by this share of its distance, or the spec is ambiguous.
inline constexpr double kRelationMargin = 0.02;

// Index into spec.candidates of the key. Errors (naming the question's structures): a candidate
// missing from `distances`, `from` among candidates, fewer than 2 candidates, Nearest with a
// runner-up within kRelationMargin, Reachable with a threshold <= 0 or not exactly one candidate
// within it.
Result<int> relationKey(const RelationSpec& spec, const StructureDistances& distances);

// The structures met along the segment entry→target (LPS mm), in order: the path is sampled every
// quarter of the smallest voxel spacing, each sample takes the label of the voxel containing it;
// background (0), samples outside the grid and labels with no structure are ignored, and each
// structure is listed once, where it is first met.
std::vector<std::string> marchLabels(const LabelMap& labels, const std::vector<Structure>& structures,
                                     const Vec3& entryMm, const Vec3& targetMm);

// The `count` structures nearest `targetId` by weighted distance (excluding it, `exclude` and
// unreachable ones), nearest first; ties by id.
std::vector<std::string> nearestStructures(const std::string& targetId, const StructureDistances& distances,
                                           int count, const std::vector<std::string>& exclude = {});

class KeyComputer;

// Identify distractors from the target's neighbourhood, so that they cannot be ruled out by region:
// among the structures reachable from `targetId` (finite weighted distance), the `count` whose
// centroids lie nearest the target's centroid; ties by weighted distance, then by id.
Result<std::vector<std::string>> neighbourhoodDistractors(const std::string& targetId,
                                                          const StructureDistances& distances, int count,
                                                          KeyComputer& keys);

// Deterministic permutation of `items` seeded by `seed` (a question id): the same question always
// shows its choices in the same order, also after resuming.
std::vector<std::string> stableShuffle(std::vector<std::string> items, const std::string& seed);

// Supplies dataset facts to key computation. Implementations may cache.
class KeyComputer {
 public:
  virtual ~KeyComputer() = default;
  virtual bool hasStructure(const std::string& structureId) const = 0;
  virtual Result<StructureDistances> distancesFrom(const std::string& structureId) = 0;
  virtual Result<Vec3> centroidMm(const std::string& structureId) = 0;
  virtual Result<std::vector<std::string>> structuresAlong(const Vec3& entryMm, const Vec3& targetMm) = 0;
};

// Seeds (mask of one structure, on the label grid) → weighted distances on the same grid.
using DistanceFieldFunction = std::function<Result<FloatVolume>(const Mask& seeds)>;

// KeyComputer over a Dataset that outlives it; one distance field per source structure, cached.
class DatasetKeyComputer final : public KeyComputer {
 public:
  DatasetKeyComputer(const Dataset& dataset, DistanceFieldFunction distanceField);
  bool hasStructure(const std::string& structureId) const override;
  Result<StructureDistances> distancesFrom(const std::string& structureId) override;
  Result<Vec3> centroidMm(const std::string& structureId) override;
  Result<std::vector<std::string>> structuresAlong(const Vec3& entryMm, const Vec3& targetMm) override;

 private:
  const Dataset& dataset_;
  DistanceFieldFunction distanceField_;
  std::map<std::string, StructureDistances> cache_;
};

// Computes the dataset-dependent parts of `question` (choices, keyChoice, keyOrder) and checks
// every structure id it names. Errors name the question id and the bad field.
Result<ResolvedQuestion> resolveQuestion(const Question& question, KeyComputer& keys);

}  // namespace at::quiz
