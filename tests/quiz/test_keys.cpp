#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "quiz/keys.h"
#include "volume/mask.h"

using namespace at;
using namespace at::quiz;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A structure known by its label, id and name alone (no browsing group, no description).
Structure named(std::uint16_t label, std::string id, std::string displayName) {
  return {.label = label, .id = std::move(id), .displayName = std::move(displayName), .system = "", .description = ""};
}

// A 20×5×5 grid of 1 mm voxels at the origin with three slabs along x:
//   x:   0 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19
//   lab: 0 0 1 1 0 0 2 2 2 0 0  1  1  0  3  3  0  0  0  0     (a = 1, b = 2, c = 3)
Dataset slabs() {
  Dataset d;
  d.id = "slabs";
  Geometry g;
  g.dims = {20, 5, 5};
  d.volume = Volume(g, 0);
  d.labels = LabelMap(g, 0);
  const int labelAt[20] = {0, 0, 1, 1, 0, 0, 2, 2, 2, 0, 0, 1, 1, 0, 3, 3, 0, 0, 0, 0};
  for (int k = 0; k < 5; ++k)
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 20; ++i) d.labels.at(i, j, k) = std::uint16_t(labelAt[i]);
  d.structures = {named(1, "a", "A"), named(2, "b", "B"), named(3, "c", "C"), named(4, "empty", "Empty")};
  return d;
}

// Euclidean distance to the nearest seed voxel (brute force): a stand-in for the WDT.
Result<FloatVolume> euclidean(const Mask& seeds) {
  FloatVolume out(seeds.geometry, std::numeric_limits<float>::infinity());
  const Dims& n = seeds.dims();
  std::vector<Vec3> points;
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i)
        if (seeds.at(i, j, k)) points.push_back({double(i), double(j), double(k)});
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i)
        for (const Vec3& p : points)
          out.at(i, j, k) = std::min(out.at(i, j, k), float(norm(p - Vec3{double(i), double(j), double(k)})));
  return out;
}

}  // namespace

TEST_CASE("MarchLabels_ListsStructuresInOrderOnceIgnoringBackground") {
  const Dataset d = slabs();
  // a → b → a again → c: "a" is listed once, where first met.
  CHECK(marchLabels(d.labels, d.structures, {-5, 2, 2}, {25, 2, 2}) == std::vector<std::string>{"a", "b", "c"});
  CHECK(marchLabels(d.labels, d.structures, {25, 2, 2}, {-5, 2, 2}) == std::vector<std::string>{"c", "a", "b"});
  CHECK(marchLabels(d.labels, d.structures, {7, 2, 2}, {15, 2, 2}) == std::vector<std::string>{"b", "a", "c"});
  CHECK(marchLabels(d.labels, d.structures, {4, 2, 2}, {5, 2, 2}).empty());        // background only
  CHECK(marchLabels(d.labels, d.structures, {0, 20, 2}, {19, 20, 2}).empty());     // outside the grid
  CHECK(marchLabels(d.labels, d.structures, {7, 2, 2}, {7, 2, 2}) == std::vector<std::string>{"b"});  // a point
}

TEST_CASE("MarchLabels_ThinStructureCrossedObliquely_IsNotSkipped") {
  Geometry g;
  g.dims = {10, 10, 1};
  LabelMap labels(g, 0);
  for (int j = 0; j < 10; ++j) labels.at(5, j, 0) = 1;  // a one-voxel wall at x = 5
  const std::vector<Structure> s = {named(1, "wall", "Wall")};
  CHECK(marchLabels(labels, s, {0, 0, 0}, {9, 9, 0}) == std::vector<std::string>{"wall"});
  CHECK(marchLabels(labels, s, {0, 9, 0}, {9, 0.3, 0}) == std::vector<std::string>{"wall"});
}

TEST_CASE("RelationKey_NearestAndReachable") {
  const StructureDistances d = {{"vestibule", 0.05}, {"carotid_canal", 2.1}, {"sigmoid_sinus", 9.0},
                                {"stapes", 0.5}, {"far", kInf}};
  RelationSpec nearest{"cochlea", RelationKind::Nearest, {"sigmoid_sinus", "vestibule", "carotid_canal"}};
  CHECK(relationKey(nearest, d) == 1);
  RelationSpec reachable{"cochlea", RelationKind::Reachable, {"sigmoid_sinus", "carotid_canal", "vestibule"}, 1.0};
  CHECK(relationKey(reachable, d) == 2);
  RelationSpec boundary{"cochlea", RelationKind::Reachable, {"sigmoid_sinus", "carotid_canal"}, 2.1};
  CHECK(relationKey(boundary, d) == 1);  // exactly at the threshold counts
}

TEST_CASE("RelationKey_AmbiguousOrBadSpecs_AreErrorsNamingTheStructures") {
  const StructureDistances d = {{"a", 1.0}, {"b", 1.01}, {"c", 5}, {"far", kInf}, {"far2", kInf}};
  auto tie = relationKey({"x", RelationKind::Nearest, {"a", "b", "c"}}, d);
  REQUIRE_FALSE(tie);
  CHECK(tie.error().message.find("ambiguous") != std::string::npos);
  CHECK(tie.error().message.find("'a'") != std::string::npos);
  CHECK_FALSE(relationKey({"x", RelationKind::Nearest, {"a"}}, d));
  CHECK_FALSE(relationKey({"x", RelationKind::Nearest, {"a", "missing"}}, d));
  CHECK_FALSE(relationKey({"a", RelationKind::Nearest, {"a", "c"}}, d));
  CHECK_FALSE(relationKey({"x", RelationKind::Nearest, {"far", "far2"}}, d));
  CHECK_FALSE(relationKey({"x", RelationKind::Reachable, {"a", "b", "c"}, 2.0}, d));  // two within
  CHECK_FALSE(relationKey({"x", RelationKind::Reachable, {"c", "far"}, 2.0}, d));     // none within
  CHECK_FALSE(relationKey({"x", RelationKind::Reachable, {"a", "c"}, 0.0}, d));
}

TEST_CASE("NearestStructures_RanksByDistanceThenIdAndSkipsUnreachable") {
  const StructureDistances d = {{"t", 0}, {"b", 2}, {"a", 2}, {"c", 1}, {"far", kInf}, {"d", 3}};
  CHECK(nearestStructures("t", d, 3) == std::vector<std::string>{"c", "a", "b"});
  CHECK(nearestStructures("t", d, 10, {"a"}) == std::vector<std::string>{"c", "b", "d"});
}

TEST_CASE("StableShuffle_IsAPermutationAndDependsOnlyOnTheSeed") {
  const std::vector<std::string> items = {"a", "b", "c", "d", "e", "f"};
  const auto once = stableShuffle(items, "lesson.q1");
  CHECK(once == stableShuffle(items, "lesson.q1"));
  auto sorted = once;
  std::sort(sorted.begin(), sorted.end());
  CHECK(sorted == items);
  bool differs = false;
  for (const char* seed : {"q2", "q3", "q4", "q5"}) differs = differs || stableShuffle(items, seed) != once;
  CHECK(differs);
}

TEST_CASE("DatasetKeyComputer_DistancesAreTheFieldMinimumOverEachStructure") {
  const Dataset d = slabs();
  DatasetKeyComputer keys(d, euclidean);
  auto fromB = keys.distancesFrom("b");
  REQUIRE(fromB);
  // b occupies x 6..8; a's nearest voxel is x=3 (3 mm) or x=11 (3 mm); c's nearest x=14 (6 mm).
  CHECK((*fromB)["b"] == doctest::Approx(0));
  CHECK((*fromB)["a"] == doctest::Approx(3));
  CHECK((*fromB)["c"] == doctest::Approx(6));
  CHECK(std::isinf((*fromB)["empty"]));
  CHECK_FALSE(keys.distancesFrom("nope"));
  auto centroid = keys.centroidMm("c");
  REQUIRE(centroid);
  CHECK((*centroid)[0] == doctest::Approx(14.5));
  CHECK_FALSE(keys.centroidMm("empty"));
}

TEST_CASE("ResolveQuestion_ComputesKeysForEveryDatasetDependentKind") {
  const Dataset d = slabs();
  DatasetKeyComputer keys(d, euclidean);

  Question identify;
  identify.id = "t.identify";
  identify.kind = QuestionKind::Identify;
  identify.target = "c";
  identify.distractors = 1;
  auto ri = resolveQuestion(identify, keys);
  REQUIRE(ri);
  REQUIRE(ri->choices.size() == 2);
  CHECK(ri->choices[std::size_t(ri->keyChoice)] == "c");
  CHECK(std::find(ri->choices.begin(), ri->choices.end(), "a") != ri->choices.end());  // a is 2 mm from c, b 6 mm

  Question relation;
  relation.id = "t.relation";
  relation.kind = QuestionKind::Relation;
  relation.target = "b";
  relation.relation = {"b", RelationKind::Nearest, {"c", "a"}};
  auto rr = resolveQuestion(relation, keys);
  REQUIRE(rr);
  CHECK(rr->keyChoice == 1);

  Question order;
  order.id = "t.order";
  order.kind = QuestionKind::Order;
  order.target = "c";
  order.order.entryMm = Vec3{-5, 2, 2};
  order.order.targetStructure = "c";
  order.order.extraChoices = 0;
  auto ro = resolveQuestion(order, keys);
  REQUIRE(ro);
  CHECK(ro->keyOrder == std::vector<std::string>{"a", "b", "c"});
  CHECK(ro->choices != ro->keyOrder);  // offered shuffled
  CHECK(ro->choices.size() == 3);
}

TEST_CASE("ResolveQuestion_BadReferences_AreErrorsNamingQuestionAndField") {
  const Dataset d = slabs();
  DatasetKeyComputer keys(d, euclidean);
  Question q;
  q.id = "t.bad";
  q.kind = QuestionKind::Locate;
  q.target = "nope";
  auto r = resolveQuestion(q, keys);
  REQUIRE_FALSE(r);
  CHECK(r.error().message == "question t.bad: target: unknown structure 'nope'");

  q.target = "a";
  q.kind = QuestionKind::Identify;
  q.choices = {"b", "c"};
  r = resolveQuestion(q, keys);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("choices") != std::string::npos);

  q.kind = QuestionKind::Order;
  q.choices.clear();
  q.order = {};
  q.order.entryMm = Vec3{4, 2, 2};
  q.order.targetMm = Vec3{5, 2, 2};
  r = resolveQuestion(q, keys);
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("meets 0 structure") != std::string::npos);

  q.order.entryStructure = "a";  // both forms for the entry
  CHECK_FALSE(resolveQuestion(q, keys));
}
