// A small course on a toy dataset for the db tests: five structures on a line, a KeyComputer whose
// weighted distances are the distances along that line, and two lessons using every question kind.
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "db/sql_repositories.h"
#include "lessons/curriculum.h"
#include "quiz/keys.h"

namespace at::test {

// Structures a..e at x = 0, 10, 20, 30, 40 mm (label = index + 1).
inline std::vector<Structure> toyStructures() {
  const char* ids[] = {"malleus", "incus", "stapes", "cochlea", "facial_nerve"};
  const char* names[] = {"Malleus", "Incus", "Stapes", "Cochlea", "Facial nerve"};
  std::vector<Structure> out;
  for (int i = 0; i < 5; ++i) {
    Structure s;
    s.label = std::uint16_t(i + 1);
    s.id = ids[i];
    s.displayName = names[i];
    out.push_back(s);
  }
  return out;
}

inline db::BuiltinStructures toyBuiltin() {
  return [](const std::string& id) -> std::optional<std::vector<Structure>> {
    if (id == "toy") return toyStructures();
    return std::nullopt;
  };
}

class ToyKeys final : public quiz::KeyComputer {
 public:
  bool hasStructure(const std::string& id) const override { return index(id) >= 0; }
  Result<quiz::StructureDistances> distancesFrom(const std::string& id) override {
    const int from = index(id);
    if (from < 0) return fail("unknown structure '" + id + "'");
    quiz::StructureDistances d;
    for (const auto& s : toyStructures()) d[s.id] = 10.0 * std::abs(index(s.id) - from);
    return d;
  }
  Result<Vec3> centroidMm(const std::string& id) override {
    const int i = index(id);
    if (i < 0) return fail("unknown structure '" + id + "'");
    return Vec3{10.0 * i, 0, 0};
  }
  Result<std::vector<std::string>> structuresAlong(const Vec3& entry, const Vec3& target) override {
    std::vector<std::string> out;
    const auto all = toyStructures();
    const double lo = std::min(entry[0], target[0]), hi = std::max(entry[0], target[0]);
    for (int i = 0; i < 5; ++i)
      if (10.0 * i >= lo - 1e-9 && 10.0 * i <= hi + 1e-9) out.push_back(all[std::size_t(i)].id);
    if (entry[0] > target[0]) std::reverse(out.begin(), out.end());
    return out;
  }

 private:
  static int index(const std::string& id) {
    const auto all = toyStructures();
    for (std::size_t i = 0; i < all.size(); ++i)
      if (all[i].id == id) return int(i);
    return -1;
  }
};

inline lessons::Step showStep(const std::string& structure, const std::string& text) {
  lessons::Step s;
  s.kind = lessons::StepKind::Show;
  s.show.structure = structure;
  s.show.presetId = structure + "_wdt";
  s.show.view = lessons::CameraView::LateralLeft;
  s.show.title = "About the " + structure;
  s.show.text = text;
  return s;
}

inline lessons::Step questionStep(quiz::Question q) {
  lessons::Step s;
  s.kind = lessons::StepKind::Question;
  s.question = std::move(q);
  return s;
}

// Two lessons; "toy.middle" needs "toy.ossicles". Every question kind appears.
inline lessons::Course toyCourse(int version = 1) {
  lessons::Course c;
  c.id = "toy";
  c.title = "Toy ear";
  c.summary = "A course for tests";
  c.datasetId = "toy";
  c.version = version;
  c.synonyms["stapes"] = {"stirrup"};

  lessons::Lesson a;
  a.id = "toy.ossicles";
  a.courseId = c.id;
  a.title = "Ossicles";
  a.summary = "Three small bones";
  a.steps.push_back(showStep("stapes", "The stapes is the smallest bone; its footplate sits in the oval window."));
  quiz::Question name;
  name.id = "toy.ossicles.name_stapes";
  name.kind = quiz::QuestionKind::Name;
  name.prompt = "Name the highlighted bone.";
  name.target = "stapes";
  a.steps.push_back(questionStep(name));
  quiz::Question identify;
  identify.id = "toy.ossicles.identify_incus";
  identify.kind = quiz::QuestionKind::Identify;
  identify.prompt = "Which structure is highlighted?";
  identify.target = "incus";
  identify.choices = {"malleus", "incus", "stapes"};
  a.steps.push_back(questionStep(identify));
  quiz::Question locate;
  locate.id = "toy.ossicles.locate_malleus";
  locate.kind = quiz::QuestionKind::Locate;
  locate.prompt = "Click the malleus.";
  locate.target = "malleus";
  locate.toleranceMm = 0.5;
  a.steps.push_back(questionStep(locate));
  a.steps.back().scene = lessons::QuestionScene{.structure = "incus",
                                                 .presetId = "incus_wdt",
                                                 .view = lessons::CameraView::LateralRight,
                                                 .camera = std::nullopt,
                                                 .clip = std::nullopt};
  c.lessons.push_back(a);

  lessons::Lesson b;
  b.id = "toy.middle";
  b.courseId = c.id;
  b.title = "Around the middle ear";
  b.prerequisites = {"toy.ossicles"};
  b.steps.push_back(showStep("cochlea", "The cochlea is the hearing organ, medial to the middle ear."));
  quiz::Question relation;
  relation.id = "toy.middle.nearest_to_stapes";
  relation.kind = quiz::QuestionKind::Relation;
  relation.prompt = "Which is nearest to the stapes?";
  relation.target = "stapes";
  relation.relation.from = "stapes";
  relation.relation.kind = quiz::RelationKind::Nearest;
  relation.relation.candidates = {"malleus", "cochlea", "facial_nerve"};
  b.steps.push_back(questionStep(relation));
  quiz::Question order;
  order.id = "toy.middle.order_drill";
  order.kind = quiz::QuestionKind::Order;
  order.prompt = "Drilling from the malleus to the cochlea, in what order are structures met?";
  order.target = "cochlea";
  order.order.entryStructure = "malleus";
  order.order.targetStructure = "cochlea";
  order.order.extraChoices = 1;
  b.steps.push_back(questionStep(order));
  quiz::Question identify2;
  identify2.id = "toy.middle.identify_cochlea";
  identify2.kind = quiz::QuestionKind::Identify;
  identify2.prompt = "Which structure is this?";
  identify2.target = "cochlea";
  identify2.distractors = 2;
  b.steps.push_back(questionStep(identify2));
  c.lessons.push_back(b);
  return c;
}

}  // namespace at::test
