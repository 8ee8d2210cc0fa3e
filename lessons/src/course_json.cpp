#include "lessons/course_json.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/json_document.h"
#include "core/printable_text.h"
#include "core/regular_file.h"

namespace at::lessons {
namespace {

using nlohmann::json;

constexpr int kSchema = 1;
// The default course is 26 KB; anything near this is not a course.
constexpr std::size_t kMaxCourseBytes = std::size_t(64) << 20;

// Reads one JSON object strictly: every key must be known, types checked, errors name the path.
class Reader {
 public:
  Reader(const json& object, std::string path) : j_(object), path_(std::move(path)) {}

  // Call first: the value must be an object whose keys are all in `allowed`.
  Status expect(std::initializer_list<const char*> allowed) const {
    if (!j_.is_object()) return fail((path_.empty() ? std::string("the document") : path_) + ": must be an object");
    for (const auto& [key, value] : j_.items()) {
      bool known = false;
      for (const char* a : allowed) known = known || key == a;
      if (!known) return fail(field(key) + ": unknown field");
    }
    return {};
  }

  // Keys come from the file: quoted printably (a key may hold a newline or an escape sequence).
  std::string field(const std::string& key) const {
    const std::string shown = printableText(key, 60);
    return path_.empty() ? shown : path_ + "." + shown;
  }
  bool has(const char* key) const { return j_.contains(key); }
  const json& raw(const char* key) const { return j_.at(key); }

  Result<std::string> string(const char* key, bool required, std::string fallback = {}) const {
    if (!j_.contains(key)) {
      if (required) return fail(field(key) + ": missing");
      return fallback;
    }
    if (!j_[key].is_string()) return fail(field(key) + ": must be a string");
    std::string value = j_[key].get<std::string>();
    if (required && value.empty()) return fail(field(key) + ": must not be empty");
    return value;
  }

  Result<double> number(const char* key, double fallback) const {
    if (!j_.contains(key)) return fallback;
    if (!j_[key].is_number()) return fail(field(key) + ": must be a number");
    return j_[key].get<double>();
  }

  Result<bool> boolean(const char* key, bool fallback) const {
    if (!j_.contains(key)) return fallback;
    if (!j_[key].is_boolean()) return fail(field(key) + ": must be true or false");
    return j_[key].get<bool>();
  }

  Result<int> integer(const char* key, int fallback) const {
    if (!j_.contains(key)) return fallback;
    const json& v = j_[key];
    if (!v.is_number_integer()) return fail(field(key) + ": must be an integer");
    // An unsigned value above INT64_MAX or a signed one outside int does not fit.
    if (v.is_number_unsigned() ? v.get<std::uint64_t>() > std::uint64_t(std::numeric_limits<int>::max())
                               : (v.get<std::int64_t>() < std::numeric_limits<int>::min() ||
                                  v.get<std::int64_t>() > std::numeric_limits<int>::max()))
      return fail(field(key) + ": must be an integer of at most 9 digits");
    return v.get<int>();
  }

  Result<std::vector<std::string>> strings(const char* key) const {
    std::vector<std::string> out;
    if (!j_.contains(key)) return out;
    if (!j_[key].is_array()) return fail(field(key) + ": must be an array of strings");
    for (std::size_t i = 0; i < j_[key].size(); ++i) {
      const json& item = j_[key][i];
      if (!item.is_string() || item.get<std::string>().empty()) {
        return fail(field(key) + "[" + std::to_string(i) + "]: must be a non-empty string");
      }
      out.push_back(item.get<std::string>());
    }
    return out;
  }

  Result<std::optional<Vec3>> point(const char* key) const {
    if (!j_.contains(key)) return std::optional<Vec3>{};
    const json& v = j_[key];
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
      return fail(field(key) + ": must be [x, y, z] in millimetres");
    }
    return std::optional<Vec3>(Vec3{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()});
  }

 private:
  const json& j_;
  std::string path_;
};

#define AT_TRY(var, expr)                                   \
  auto var##_result = (expr);                               \
  if (!var##_result) return tl::unexpected(var##_result.error()); \
  auto var = std::move(*var##_result)

Result<quiz::Question> readQuestion(const json& j, const std::string& path) {
  Reader r(j, path);
  if (auto ok = r.expect({"id", "kind", "prompt", "target", "tolerance_mm", "choices", "distractors", "synonyms",
                          "ask_side", "relation", "order", "difficulty", "explanation"});
      !ok) {
    return tl::unexpected(ok.error());
  }
  quiz::Question q;
  AT_TRY(id, r.string("id", true));
  AT_TRY(kindText, r.string("kind", true));
  auto kind = quiz::parseQuestionKind(kindText);
  if (!kind) return tl::unexpected(withContext(r.field("kind"), kind.error()));
  AT_TRY(prompt, r.string("prompt", true));
  AT_TRY(target, r.string("target", true));
  AT_TRY(tolerance, r.number("tolerance_mm", 0));
  AT_TRY(choices, r.strings("choices"));
  AT_TRY(distractors, r.integer("distractors", 3));
  AT_TRY(synonyms, r.strings("synonyms"));
  AT_TRY(askSide, r.boolean("ask_side", false));
  AT_TRY(difficulty, r.number("difficulty", 1500));
  AT_TRY(explanation, r.string("explanation", false));
  q.id = id;
  q.kind = *kind;
  q.prompt = prompt;
  q.target = target;
  q.toleranceMm = tolerance;
  q.choices = choices;
  q.distractors = distractors;
  q.synonyms = synonyms;
  q.askSide = askSide;
  q.difficulty = difficulty;
  q.explanation = explanation;

  const auto onlyFor = [&](const char* key, quiz::QuestionKind k) -> Status {
    if (r.has(key) && q.kind != k) {
      return fail(r.field(key) + ": only allowed for " + quiz::toString(k) + " questions");
    }
    return {};
  };
  for (auto [key, k] : {std::pair{"tolerance_mm", quiz::QuestionKind::Locate},
                        std::pair{"choices", quiz::QuestionKind::Identify},
                        std::pair{"distractors", quiz::QuestionKind::Identify},
                        std::pair{"synonyms", quiz::QuestionKind::Name},
                        std::pair{"ask_side", quiz::QuestionKind::Name},
                        std::pair{"relation", quiz::QuestionKind::Relation},
                        std::pair{"order", quiz::QuestionKind::Order}}) {
    if (auto ok = onlyFor(key, k); !ok) return tl::unexpected(ok.error());
  }
  if (q.toleranceMm < 0) return fail(r.field("tolerance_mm") + ": must be >= 0");
  if (q.distractors < 1) return fail(r.field("distractors") + ": must be >= 1");
  if (!(q.difficulty > 0 && q.difficulty < 4000)) return fail(r.field("difficulty") + ": must be an Elo rating in 0..4000");

  if (q.kind == quiz::QuestionKind::Relation) {
    if (!r.has("relation")) return fail(r.field("relation") + ": missing");
    Reader rel(r.raw("relation"), r.field("relation"));
    if (auto ok = rel.expect({"from", "kind", "candidates", "threshold_mm"}); !ok) return tl::unexpected(ok.error());
    AT_TRY(from, rel.string("from", true));
    AT_TRY(relKindText, rel.string("kind", true));
    auto relKind = quiz::parseRelationKind(relKindText);
    if (!relKind) return tl::unexpected(withContext(rel.field("kind"), relKind.error()));
    AT_TRY(candidates, rel.strings("candidates"));
    AT_TRY(threshold, rel.number("threshold_mm", 0));
    if (candidates.size() < 2) return fail(rel.field("candidates") + ": needs at least 2 structure ids");
    if (*relKind == quiz::RelationKind::Reachable && !(threshold > 0)) {
      return fail(rel.field("threshold_mm") + ": reachable needs a threshold > 0");
    }
    if (*relKind == quiz::RelationKind::Nearest && rel.has("threshold_mm")) {
      return fail(rel.field("threshold_mm") + ": only allowed for reachable");
    }
    q.relation = quiz::RelationSpec{from, *relKind, candidates, threshold};
  }
  if (q.kind == quiz::QuestionKind::Order) {
    if (!r.has("order")) return fail(r.field("order") + ": missing");
    Reader ord(r.raw("order"), r.field("order"));
    if (auto ok = ord.expect({"entry_mm", "target_mm", "entry_structure", "target_structure", "extra_choices"}); !ok) {
      return tl::unexpected(ok.error());
    }
    AT_TRY(entryMm, ord.point("entry_mm"));
    AT_TRY(targetMm, ord.point("target_mm"));
    AT_TRY(entryStructure, ord.string("entry_structure", false));
    AT_TRY(targetStructure, ord.string("target_structure", false));
    AT_TRY(extra, ord.integer("extra_choices", 2));
    if (entryMm.has_value() == !entryStructure.empty()) {
      return fail(ord.field("entry_mm") + ": give exactly one of entry_mm and entry_structure");
    }
    if (targetMm.has_value() == !targetStructure.empty()) {
      return fail(ord.field("target_mm") + ": give exactly one of target_mm and target_structure");
    }
    if (extra < 0) return fail(ord.field("extra_choices") + ": must be >= 0");
    q.order = quiz::OrderSpec{entryMm, targetMm, entryStructure, targetStructure, extra};
  }
  return q;
}

// [x, y, z] of finite numbers at `path`.
Result<Vec3> readVector(const json& v, const std::string& path, const char* what) {
  if (!v.is_array() || v.size() != 3) return fail(path + ": must be " + what);
  Vec3 out{};
  for (std::size_t i = 0; i < 3; ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) return fail(path + ": must be " + what);
    out[i] = v[i].get<double>();
  }
  return out;
}

// "camera": {"target_mm": [x, y, z], "look": [x, y, z], "up": [x, y, z], "distance_mm": D}
// (curriculum.h, StepCamera); look and up are normalised, up made orthogonal to look.
Result<StepCamera> readCamera(const json& j, const std::string& path) {
  Reader r(j, path);
  if (auto ok = r.expect({"target_mm", "look", "up", "distance_mm"}); !ok) return tl::unexpected(ok.error());
  for (const char* key : {"target_mm", "look", "up", "distance_mm"})
    if (!r.has(key)) return fail(r.field(key) + ": missing");
  StepCamera c;
  AT_TRY(target, readVector(r.raw("target_mm"), r.field("target_mm"), "[x, y, z] in millimetres"));
  AT_TRY(look, readVector(r.raw("look"), r.field("look"), "a direction [x, y, z]"));
  AT_TRY(up, readVector(r.raw("up"), r.field("up"), "a direction [x, y, z]"));
  AT_TRY(distance, r.number("distance_mm", 0));
  if (!std::isfinite(distance) || distance <= 0 || distance > 1e5)
    return fail(r.field("distance_mm") + ": must be a distance in millimetres above 0 (at most 100000)");
  // Directions already unit and square (as written back) are kept bit for bit.
  const double lookLength = std::sqrt(dot(look, look));
  if (lookLength < 1e-9) return fail(r.field("look") + ": must not be zero");
  if (std::abs(lookLength - 1) > 1e-12) look = (1.0 / lookLength) * look;
  if (std::abs(dot(up, look)) > 1e-12) up = up - dot(up, look) * look;  // the part of `up` across the line of sight
  const double upLength = std::sqrt(dot(up, up));
  if (upLength < 1e-6) return fail(r.field("up") + ": must not be zero or along 'look'");
  if (std::abs(upLength - 1) > 1e-12) up = (1.0 / upLength) * up;
  c.targetMm = target;
  c.look = look;
  c.up = up;
  c.distanceMm = distance;
  return c;
}

// "clip": [nx, ny, nz, d] (curriculum.h, StepClip): the normal along one patient axis.
Result<StepClip> readClip(const json& v, const std::string& path) {
  const char* shape = "[nx, ny, nz, d]: a plane whose normal is one patient axis (e.g. [0, -1, 0, 12.5])";
  if (!v.is_array() || v.size() != 4) return fail(path + ": must be " + shape);
  std::array<double, 4> n{};
  for (std::size_t i = 0; i < 4; ++i) {
    if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) return fail(path + ": must be " + shape);
    n[i] = v[i].get<double>();
  }
  int axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (n[std::size_t(i)] == 0) continue;
    if (axis >= 0) return fail(path + ": the normal must lie along one patient axis (x, y or z), as the desktop's clip control offers");
    axis = i;
  }
  if (axis < 0) return fail(path + ": the normal must not be zero");
  StepClip c;
  const double length = std::abs(n[std::size_t(axis)]);
  c.normal = {0, 0, 0};
  c.normal[std::size_t(axis)] = n[std::size_t(axis)] > 0 ? 1 : -1;
  c.d = n[3] / length;
  return c;
}

// A step's optional "camera" and "clip".
Status readPlacement(const Reader& r, std::optional<StepCamera>& camera, std::optional<StepClip>& clip) {
  if (r.has("camera")) {
    AT_TRY(c, readCamera(r.raw("camera"), r.field("camera")));
    camera = c;
  }
  if (r.has("clip")) {
    AT_TRY(c, readClip(r.raw("clip"), r.field("clip")));
    clip = c;
  }
  return {};
}

void writePlacement(json& j, const std::optional<StepCamera>& camera, const std::optional<StepClip>& clip) {
  if (camera)
    j["camera"] = {{"target_mm", camera->targetMm}, {"look", camera->look}, {"up", camera->up}, {"distance_mm", camera->distanceMm}};
  if (clip) j["clip"] = {clip->normal[0], clip->normal[1], clip->normal[2], clip->d};
}

Result<Step> readStep(const json& j, const std::string& path) {
  Reader r(j, path);
  if (!j.is_object()) return fail(path + ": must be an object");
  AT_TRY(kindText, r.string("kind", true));
  auto kind = parseStepKind(kindText);
  if (!kind) return tl::unexpected(withContext(r.field("kind"), kind.error()));
  Step step;
  step.kind = *kind;
  if (step.kind == StepKind::Show) {
    if (auto ok = r.expect({"kind", "structure", "preset", "view", "title", "text", "camera", "clip"}); !ok) {
      return tl::unexpected(ok.error());
    }
    AT_TRY(structure, r.string("structure", true));
    AT_TRY(preset, r.string("preset", true));
    AT_TRY(viewText, r.string("view", true));
    auto view = parseCameraView(viewText);
    if (!view) return tl::unexpected(withContext(r.field("view"), view.error()));
    AT_TRY(title, r.string("title", true));
    AT_TRY(text, r.string("text", true));
    step.show = ShowStep{structure, preset, *view, title, text, std::nullopt, std::nullopt};
    if (auto ok = readPlacement(r, step.show.camera, step.show.clip); !ok) return tl::unexpected(ok.error());
  } else if (step.kind == StepKind::Question) {
    if (auto ok = r.expect({"kind", "question", "structure", "preset", "view", "camera", "clip"}); !ok)
      return tl::unexpected(ok.error());
    if (!r.has("question")) return fail(r.field("question") + ": missing");
    AT_TRY(question, readQuestion(r.raw("question"), r.field("question")));
    step.question = question;
    // The scene shown while the question is asked (curriculum.h, QuestionScene).
    if (r.has("structure") || r.has("preset") || r.has("view") || r.has("camera") || r.has("clip")) {
      QuestionScene scene;
      AT_TRY(structure, r.string("structure", false, question.target));
      AT_TRY(preset, r.string("preset", false));
      AT_TRY(viewText, r.string("view", false, toString(CameraView::LateralRight)));
      auto view = parseCameraView(viewText);
      if (!view) return fail(r.field("view") + ": " + view.error().message);
      scene.structure = structure;
      scene.presetId = preset;
      scene.view = *view;
      if (auto ok = readPlacement(r, scene.camera, scene.clip); !ok) return tl::unexpected(ok.error());
      step.scene = scene;
    }
    if (question.kind == quiz::QuestionKind::Locate) {
      if (!step.scene || !r.has("structure"))
        return fail(r.field("structure") + ": a locate question needs the structure whose view shows the region "
                                           "(a neighbour of '" + question.target + "'), with its view");
      if (step.scene->structure == question.target)
        return fail(r.field("structure") + ": a locate question must not select its target '" + question.target +
                    "' (it would be highlighted); select a neighbour whose context shows it");
    }
  } else {
    if (auto ok = r.expect({"kind", "structure", "items"}); !ok) return tl::unexpected(ok.error());
    AT_TRY(structure, r.string("structure", true));
    AT_TRY(items, r.strings("items"));
    if (items.empty()) return fail(r.field("items") + ": needs at least one Likert item");
    step.study = StudyStep{structure, items};
  }
  return step;
}

Result<Lesson> readLesson(const json& j, const std::string& path, const std::string& courseId) {
  Reader r(j, path);
  if (auto ok = r.expect({"id", "title", "summary", "prerequisites", "steps"}); !ok) return tl::unexpected(ok.error());
  Lesson lesson;
  lesson.courseId = courseId;
  AT_TRY(id, r.string("id", true));
  AT_TRY(title, r.string("title", true));
  AT_TRY(summary, r.string("summary", false));
  AT_TRY(prerequisites, r.strings("prerequisites"));
  lesson.id = id;
  lesson.title = title;
  lesson.summary = summary;
  lesson.prerequisites = prerequisites;
  if (!r.has("steps") || !r.raw("steps").is_array() || r.raw("steps").empty()) {
    return fail(r.field("steps") + ": must be a non-empty array");
  }
  for (std::size_t i = 0; i < r.raw("steps").size(); ++i) {
    AT_TRY(step, readStep(r.raw("steps")[i], r.field("steps") + "[" + std::to_string(i) + "]"));
    lesson.steps.push_back(std::move(step));
  }
  return lesson;
}

Result<ExamSpec> readExam(const json& j, const std::string& path) {
  Reader r(j, path);
  if (auto ok = r.expect({"id", "title", "instructions", "structures", "kinds", "count", "time_limit_s",
                          "locate_views", "pass_score", "prerequisites"});
      !ok) {
    return tl::unexpected(ok.error());
  }
  ExamSpec exam;
  AT_TRY(id, r.string("id", true));
  AT_TRY(title, r.string("title", true));
  AT_TRY(instructions, r.string("instructions", false));
  AT_TRY(structures, r.strings("structures"));
  AT_TRY(kindTexts, r.strings("kinds"));
  AT_TRY(views, r.strings("locate_views"));
  AT_TRY(prerequisites, r.strings("prerequisites"));
  exam.id = id;
  exam.title = title;
  exam.instructions = instructions;
  exam.prerequisites = prerequisites;
  if (structures.empty()) return fail(r.field("structures") + ": needs at least one structure id");
  for (std::size_t i = 0; i < structures.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (structures[i] == structures[k])
        return fail(r.field("structures") + "[" + std::to_string(i) + "]: '" + structures[i] + "' is listed twice");
  exam.structures = structures;
  if (kindTexts.empty()) return fail(r.field("kinds") + ": needs at least one of locate, identify, name");
  for (std::size_t i = 0; i < kindTexts.size(); ++i) {
    const std::string at = r.field("kinds") + "[" + std::to_string(i) + "]";
    auto kind = quiz::parseQuestionKind(kindTexts[i]);
    if (!kind) return fail(at + ": " + kind.error().message);
    if (*kind != quiz::QuestionKind::Locate && *kind != quiz::QuestionKind::Identify && *kind != quiz::QuestionKind::Name)
      return fail(at + ": exams draw locate, identify and name items only, not '" + kindTexts[i] + "'");
    if (std::find(exam.kinds.begin(), exam.kinds.end(), *kind) != exam.kinds.end())
      return fail(at + ": '" + kindTexts[i] + "' is listed twice");
    exam.kinds.push_back(*kind);
  }
  if (!r.has("count")) return fail(r.field("count") + ": missing");
  AT_TRY(count, r.integer("count", 0));
  const int pairs = int(exam.structures.size() * exam.kinds.size());
  if (count < 1 || count > pairs)
    return fail(r.field("count") + ": must be 1.." + std::to_string(pairs) + " (structures × kinds), not " +
                std::to_string(count));
  exam.count = count;
  if (!r.has("time_limit_s")) return fail(r.field("time_limit_s") + ": missing");
  AT_TRY(limit, r.integer("time_limit_s", 0));
  if (limit < 1 || limit > 86400) return fail(r.field("time_limit_s") + ": must be 1..86400 seconds");
  exam.timeLimitS = limit;
  if (r.has("locate_views")) {
    if (std::find(exam.kinds.begin(), exam.kinds.end(), quiz::QuestionKind::Locate) == exam.kinds.end())
      return fail(r.field("locate_views") + ": only used by locate items, and kinds has no locate");
    if (views.empty()) return fail(r.field("locate_views") + ": needs at least one of 3d, slice");
    exam.locateViews.clear();
    for (std::size_t i = 0; i < views.size(); ++i) {
      auto view = parseExamLocateView(views[i]);
      if (!view) return fail(r.field("locate_views") + "[" + std::to_string(i) + "]: " + view.error().message);
      exam.locateViews.push_back(*view);
    }
  }
  if (r.has("pass_score")) {
    AT_TRY(pass, r.number("pass_score", 0));
    if (!(pass >= 0 && pass <= 1)) return fail(r.field("pass_score") + ": must be a share of 0..1");
    exam.passScore = pass;
  }
  return exam;
}

json questionJson(const quiz::Question& q) {
  json j = {{"id", q.id}, {"kind", quiz::toString(q.kind)}, {"prompt", q.prompt}, {"target", q.target},
            {"difficulty", q.difficulty}};
  if (!q.explanation.empty()) j["explanation"] = q.explanation;
  switch (q.kind) {
    case quiz::QuestionKind::Locate:
      j["tolerance_mm"] = q.toleranceMm;
      break;
    case quiz::QuestionKind::Identify:
      if (!q.choices.empty()) j["choices"] = q.choices;
      else j["distractors"] = q.distractors;
      break;
    case quiz::QuestionKind::Name:
      if (!q.synonyms.empty()) j["synonyms"] = q.synonyms;
      if (q.askSide) j["ask_side"] = true;
      break;
    case quiz::QuestionKind::Relation: {
      json rel = {{"from", q.relation.from}, {"kind", quiz::toString(q.relation.kind)},
                  {"candidates", q.relation.candidates}};
      if (q.relation.kind == quiz::RelationKind::Reachable) rel["threshold_mm"] = q.relation.thresholdMm;
      j["relation"] = rel;
      break;
    }
    case quiz::QuestionKind::Order: {
      json ord = {{"extra_choices", q.order.extraChoices}};
      if (q.order.entryMm) ord["entry_mm"] = *q.order.entryMm;
      else ord["entry_structure"] = q.order.entryStructure;
      if (q.order.targetMm) ord["target_mm"] = *q.order.targetMm;
      else ord["target_structure"] = q.order.targetStructure;
      j["order"] = ord;
      break;
    }
  }
  return j;
}

json examJson(const ExamSpec& e) {
  json kinds = json::array(), views = json::array();
  for (quiz::QuestionKind k : e.kinds) kinds.push_back(quiz::toString(k));
  for (ExamLocateView v : e.locateViews) views.push_back(toString(v));
  json x = {{"id", e.id}, {"title", e.title}, {"structures", e.structures}, {"kinds", kinds}, {"count", e.count},
            {"time_limit_s", e.timeLimitS}, {"prerequisites", e.prerequisites}};
  if (!e.instructions.empty()) x["instructions"] = e.instructions;
  if (std::find(e.kinds.begin(), e.kinds.end(), quiz::QuestionKind::Locate) != e.kinds.end()) x["locate_views"] = views;
  if (e.passScore) x["pass_score"] = *e.passScore;
  return x;
}

}  // namespace

namespace {

Result<Course> readCourse(const json& j, const std::string& sourceName) {
  const auto prefixed = [&](Error e) { return tl::unexpected(withContext(sourceName, std::move(e))); };
  Reader r(j, "");
  if (auto ok = r.expect({"schema", "id", "title", "summary", "dataset", "version", "synonyms", "lessons", "exams"}); !ok) {
    return prefixed(ok.error());
  }
  auto schema = r.integer("schema", -1);
  if (!schema) return prefixed(schema.error());
  if (*schema != kSchema) {
    return fail(sourceName + ": schema: " + (r.has("schema") ? "unsupported version " + std::to_string(*schema) : "missing") +
                " (this program reads schema " + std::to_string(kSchema) + ")");
  }
  Course course;
  const auto take = [&](auto result, auto& into) -> bool {
    if (!result) return false;
    into = std::move(*result);
    return true;
  };
  for (auto [key, into, required] : {std::tuple{"id", &course.id, true}, std::tuple{"title", &course.title, true},
                                     std::tuple{"summary", &course.summary, false},
                                     std::tuple{"dataset", &course.datasetId, true}}) {
    auto value = r.string(key, required);
    if (!take(value, *into)) return prefixed(value.error());
  }
  auto version = r.integer("version", 1);
  if (!take(version, course.version)) return prefixed(version.error());
  if (course.version < 1) return fail(sourceName + ": version: must be >= 1");

  if (r.has("synonyms")) {
    const json& syn = r.raw("synonyms");
    if (!syn.is_object()) return fail(sourceName + ": synonyms: must be an object of structure id → [names]");
    for (const auto& [structure, names] : syn.items()) {
      Reader entry(syn, "synonyms");
      auto list = entry.strings(structure.c_str());
      if (!list) return prefixed(list.error());
      course.synonyms[structure] = *list;
    }
  }

  if (!r.has("lessons") || !r.raw("lessons").is_array() || r.raw("lessons").empty()) {
    return fail(sourceName + ": lessons: must be a non-empty array");
  }
  std::set<std::string> lessonIds, questionIds;
  for (std::size_t i = 0; i < r.raw("lessons").size(); ++i) {
    const std::string path = "lessons[" + std::to_string(i) + "]";
    auto lesson = readLesson(r.raw("lessons")[i], path, course.id);
    if (!lesson) return prefixed(lesson.error());
    if (!lessonIds.insert(lesson->id).second) {
      return fail(sourceName + ": " + path + ".id: duplicate lesson id '" + lesson->id + "'");
    }
    for (std::size_t p = 0; p < lesson->prerequisites.size(); ++p) {
      const std::string& pre = lesson->prerequisites[p];
      if (pre == lesson->id || !lessonIds.count(pre)) {
        return fail(sourceName + ": " + path + ".prerequisites[" + std::to_string(p) + "]: '" + pre +
                    "' is not an earlier lesson of this course");
      }
    }
    for (std::size_t s = 0; s < lesson->steps.size(); ++s) {
      const Step& step = lesson->steps[s];
      if (step.kind == StepKind::Question && !questionIds.insert(step.question.id).second) {
        return fail(sourceName + ": " + path + ".steps[" + std::to_string(s) + "].question.id: duplicate question id '" +
                    step.question.id + "'");
      }
    }
    course.lessons.push_back(std::move(*lesson));
  }
  if (r.has("exams")) {
    if (!r.raw("exams").is_array()) return fail(sourceName + ": exams: must be an array");
    std::set<std::string> examIds;
    for (std::size_t i = 0; i < r.raw("exams").size(); ++i) {
      const std::string path = "exams[" + std::to_string(i) + "]";
      auto exam = readExam(r.raw("exams")[i], path);
      if (!exam) return prefixed(exam.error());
      if (lessonIds.count(exam->id) || !examIds.insert(exam->id).second)
        return fail(sourceName + ": " + path + ".id: '" + exam->id + "' is already a lesson or exam id");
      for (std::size_t p = 0; p < exam->prerequisites.size(); ++p)
        if (!lessonIds.count(exam->prerequisites[p]))
          return fail(sourceName + ": " + path + ".prerequisites[" + std::to_string(p) + "]: '" + exam->prerequisites[p] +
                      "' is not a lesson of this course");
      course.exams.push_back(std::move(*exam));
    }
  }
  return course;
}

}  // namespace

Result<Course> parseCourseJson(const std::string& text, const std::string& sourceName) {
  auto document = parseJsonDocument(text, sourceName);
  if (!document) return tl::unexpected(document.error());
  return withPrintableError(readCourse(*document, sourceName));
}

Result<Course> loadCourseJson(const std::filesystem::path& path) {
  auto text = readRegularFile(path.string(), path.filename().string(), kMaxCourseBytes);
  if (!text) return tl::unexpected(text.error());
  return parseCourseJson(*text, path.filename().string());
}

std::string placementToJson(const std::optional<StepCamera>& camera, const std::optional<StepClip>& clip) {
  if (!camera && !clip) return "";
  json j = json::object();
  writePlacement(j, camera, clip);
  return j.dump();
}

Status parsePlacementJson(const std::string& text, const std::string& sourceName, std::optional<StepCamera>& camera,
                          std::optional<StepClip>& clip) {
  camera.reset();
  clip.reset();
  if (text.empty()) return {};
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded()) return fail(sourceName + ": the step's camera and clip are not JSON");
  Reader r(j, sourceName);
  if (auto ok = r.expect({"camera", "clip"}); !ok) return ok;
  return readPlacement(r, camera, clip);
}

std::string courseToJson(const Course& course) {
  json lessons = json::array();
  for (const Lesson& lesson : course.lessons) {
    json steps = json::array();
    for (const Step& step : lesson.steps) {
      switch (step.kind) {
        case StepKind::Show: {
          json s = {{"kind", "show"}, {"structure", step.show.structure}, {"preset", step.show.presetId},
                    {"view", toString(step.show.view)}, {"title", step.show.title}, {"text", step.show.text}};
          writePlacement(s, step.show.camera, step.show.clip);
          steps.push_back(s);
          break;
        }
        case StepKind::Question: {
          json q = {{"kind", "question"}, {"question", questionJson(step.question)}};
          if (step.scene) {
            q["structure"] = step.scene->structure;
            if (!step.scene->presetId.empty()) q["preset"] = step.scene->presetId;
            q["view"] = toString(step.scene->view);
            writePlacement(q, step.scene->camera, step.scene->clip);
          }
          steps.push_back(q);
          break;
        }
        case StepKind::Study:
          steps.push_back({{"kind", "study"}, {"structure", step.study.structure}, {"items", step.study.items}});
          break;
      }
    }
    lessons.push_back({{"id", lesson.id}, {"title", lesson.title}, {"summary", lesson.summary},
                       {"prerequisites", lesson.prerequisites}, {"steps", steps}});
  }
  json j = {{"schema", kSchema}, {"id", course.id}, {"title", course.title}, {"summary", course.summary},
            {"dataset", course.datasetId}, {"version", course.version}, {"synonyms", course.synonyms},
            {"lessons", lessons}};
  if (!course.exams.empty()) {
    json exams = json::array();
    for (const ExamSpec& e : course.exams) exams.push_back(examJson(e));
    j["exams"] = exams;
  }
  return j.dump(2);
}

std::string questionToJson(const quiz::Question& question) { return questionJson(question).dump(); }

std::string examToJson(const ExamSpec& exam) { return examJson(exam).dump(); }

Result<ExamSpec> parseExamJson(const std::string& text, const std::string& sourceName) {
  auto j = parseJsonDocument(text, sourceName);
  if (!j) return tl::unexpected(j.error());
  auto exam = readExam(*j, "exam");
  if (!exam) return tl::unexpected(printableError(withContext(sourceName, exam.error())));
  return exam;
}

Result<quiz::Question> parseQuestionJson(const std::string& text, const std::string& sourceName) {
  auto j = parseJsonDocument(text, sourceName);
  if (!j) return tl::unexpected(j.error());
  auto q = readQuestion(*j, "question");
  if (!q) return tl::unexpected(printableError(withContext(sourceName, q.error())));
  return q;
}

}  // namespace at::lessons
