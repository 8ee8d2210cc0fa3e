#include "quiz/study_protocol.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/json_document.h"
#include "core/printable_text.h"
#include "core/regular_file.h"

namespace at::quiz {

using nlohmann::json;

std::string StudyProtocol::presetFor(const std::string& structure, int condition) const {
  auto it = presets.find(structure);
  if (it != presets.end() && condition < int(it->second.size())) return it->second[std::size_t(condition)];
  return structure + conditions.at(std::size_t(condition)).presetSuffix;
}

int unblindRating(int ratingAsShown, bool aIsFirstCondition, const StudyScale& scale) {
  return aIsFirstCondition ? ratingAsShown : scale.min + scale.max - ratingAsShown;
}

Status validParticipantId(const std::string& id) {
  const auto ok = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-'; };
  if (id.empty() || id.size() > 64 || !std::isalnum(static_cast<unsigned char>(id[0])) ||
      !std::all_of(id.begin(), id.end(), ok))
    return fail("participant id '" + id + "' must be 1 to 64 letters, digits, '_' or '-', starting with a letter or "
                "digit (it becomes the REDCap record id)");
  return {};
}

namespace {

// Strict reader: every access names the field path; leftover keys are rejected.
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  Status expectObject(const json& j, const std::string& path, const std::set<std::string>& allowed) {
    if (!j.is_object()) return fail(where(path) + " must be an object");
    for (auto it = j.begin(); it != j.end(); ++it)
      if (!allowed.count(it.key())) return fail(where(join(path, it.key())) + " is not a known field");
    return {};
  }
  Result<std::string> string(const json& j, const std::string& path) {
    if (!j.is_string()) return fail(where(path) + " must be a string");
    return j.get<std::string>();
  }
  Result<std::string> nonEmptyString(const json& j, const std::string& path) {
    auto s = string(j, path);
    if (s && s->empty()) return fail(where(path) + " must not be empty");
    return s;
  }
  Result<long long> integer(const json& j, const std::string& path) {
    if (!j.is_number_integer()) return fail(where(path) + " must be an integer");
    return j.get<long long>();
  }
  Result<double> number(const json& j, const std::string& path) {
    if (!j.is_number()) return fail(where(path) + " must be a number");
    return j.get<double>();
  }
  std::string where(const std::string& path) const { return source_ + ": field '" + path + "'"; }
  static std::string join(const std::string& a, const std::string& b) { return a.empty() ? b : a + "." + b; }
  static std::string index(const std::string& a, std::size_t i) { return a + "[" + std::to_string(i) + "]"; }

 private:
  std::string source_;
};

#define AT_TRY_ASSIGN(target, expr) \
  do {                              \
    auto at_r_ = (expr);            \
    if (!at_r_) return tl::unexpected(at_r_.error()); \
    target = *at_r_;                \
  } while (0)

}  // namespace

namespace {

// Likert scales have a handful of points; this bound keeps their arithmetic far from overflow.
constexpr int kScaleLimit = 1000;

Result<StudyProtocol> readStudyProtocol(json& j, const std::string& sourceName) {
  Reader r(sourceName);
  StudyProtocol p;
  if (auto s = r.expectObject(j, "", {"schema", "id", "title", "dataset", "structures", "conditions", "presets",
                                      "items", "scale", "groups", "seed", "t"});
      !s)
    return tl::unexpected(s.error());
  for (const char* required : {"id", "dataset", "structures", "conditions", "items", "groups"})
    if (!j.contains(required)) return fail(r.where(required) + " is missing");

  if (j.contains("schema")) {
    long long schema;
    AT_TRY_ASSIGN(schema, r.integer(j["schema"], "schema"));
    if (schema != 1) return fail(r.where("schema") + " is " + std::to_string(schema) + "; this version reads schema 1");
  }
  AT_TRY_ASSIGN(p.id, r.nonEmptyString(j["id"], "id"));
  if (j.contains("title")) AT_TRY_ASSIGN(p.title, r.string(j["title"], "title"));
  AT_TRY_ASSIGN(p.dataset, r.nonEmptyString(j["dataset"], "dataset"));

  if (!j["structures"].is_array() || j["structures"].empty())
    return fail(r.where("structures") + " must be a non-empty array of structure ids");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < j["structures"].size(); ++i) {
    std::string s;
    AT_TRY_ASSIGN(s, r.nonEmptyString(j["structures"][i], Reader::index("structures", i)));
    if (!seen.insert(s).second) return fail(r.where(Reader::index("structures", i)) + " repeats '" + s + "'");
    p.structures.push_back(s);
  }

  if (!j["conditions"].is_array() || j["conditions"].size() != 2)
    return fail(r.where("conditions") + " must list exactly two conditions (WDT first, bare second)");
  for (std::size_t i = 0; i < 2; ++i) {
    const json& c = j["conditions"][i];
    const std::string path = Reader::index("conditions", i);
    if (auto s = r.expectObject(c, path, {"id", "label", "preset_suffix"}); !s) return tl::unexpected(s.error());
    StudyCondition cond;
    if (!c.contains("id")) return fail(r.where(path + ".id") + " is missing");
    AT_TRY_ASSIGN(cond.id, r.nonEmptyString(c["id"], path + ".id"));
    if (c.contains("label")) AT_TRY_ASSIGN(cond.label, r.string(c["label"], path + ".label"));
    if (c.contains("preset_suffix")) AT_TRY_ASSIGN(cond.presetSuffix, r.string(c["preset_suffix"], path + ".preset_suffix"));
    p.conditions.push_back(cond);
  }
  if (p.conditions[0].id == p.conditions[1].id) return fail(r.where("conditions") + " must have two different ids");

  if (j.contains("presets")) {
    const json& presets = j["presets"];
    if (!presets.is_object()) return fail(r.where("presets") + " must be an object of structure → [preset, preset]");
    for (auto it = presets.begin(); it != presets.end(); ++it) {
      const std::string path = "presets." + it.key();
      if (!seen.count(it.key())) return fail(r.where(path) + " names a structure that is not in 'structures'");
      if (!it.value().is_array() || it.value().size() != 2) return fail(r.where(path) + " must be two preset ids");
      std::vector<std::string> ids(2);
      for (std::size_t c = 0; c < 2; ++c) AT_TRY_ASSIGN(ids[c], r.nonEmptyString(it.value()[c], Reader::index(path, c)));
      p.presets[it.key()] = ids;
    }
  }

  if (!j["items"].is_array() || j["items"].empty()) return fail(r.where("items") + " must be a non-empty array");
  std::set<std::string> itemIds;
  for (std::size_t i = 0; i < j["items"].size(); ++i) {
    const json& it = j["items"][i];
    const std::string path = Reader::index("items", i);
    if (auto s = r.expectObject(it, path, {"id", "wording"}); !s) return tl::unexpected(s.error());
    if (!it.contains("id") || !it.contains("wording")) return fail(r.where(path) + " needs 'id' and 'wording'");
    StudyItem item;
    AT_TRY_ASSIGN(item.id, r.nonEmptyString(it["id"], path + ".id"));
    AT_TRY_ASSIGN(item.wording, r.nonEmptyString(it["wording"], path + ".wording"));
    if (!itemIds.insert(item.id).second) return fail(r.where(path + ".id") + " repeats '" + item.id + "'");
    p.items.push_back(item);
  }

  if (j.contains("scale")) {
    const json& s = j["scale"];
    if (auto st = r.expectObject(s, "scale", {"min", "max", "anchors"}); !st) return tl::unexpected(st.error());
    long long v;
    if (s.contains("min")) {
      AT_TRY_ASSIGN(v, r.integer(s["min"], "scale.min"));
      p.scale.min = int(std::clamp<long long>(v, -kScaleLimit - 1, kScaleLimit + 1));
    }
    if (s.contains("max")) {
      AT_TRY_ASSIGN(v, r.integer(s["max"], "scale.max"));
      p.scale.max = int(std::clamp<long long>(v, -kScaleLimit - 1, kScaleLimit + 1));
    }
    for (const auto& [name, value] : {std::pair{"scale.min", p.scale.min}, std::pair{"scale.max", p.scale.max}})
      if (value < -kScaleLimit || value > kScaleLimit)
        return fail(r.where(name) + " must lie in -" + std::to_string(kScaleLimit) + ".." + std::to_string(kScaleLimit));
    if (p.scale.max <= p.scale.min || (p.scale.max - p.scale.min) % 2 != 0)
      return fail(r.where("scale") + " must have max > min and an odd number of points (a midpoint)");
    if (s.contains("anchors")) {
      if (!s["anchors"].is_object()) return fail(r.where("scale.anchors") + " must be an object of value → text");
      for (auto it = s["anchors"].begin(); it != s["anchors"].end(); ++it) {
        const std::string path = "scale.anchors." + it.key();
        int value;
        try {
          std::size_t used = 0;
          value = std::stoi(it.key(), &used);
          if (used != it.key().size()) throw std::invalid_argument("trailing");
        } catch (const std::exception&) {
          return fail(r.where(path) + " must be keyed by an integer scale value");
        }
        if (value < p.scale.min || value > p.scale.max) return fail(r.where(path) + " lies outside the scale");
        AT_TRY_ASSIGN(p.scale.anchors[value], r.nonEmptyString(it.value(), path));
      }
    }
  }

  if (!j["groups"].is_array() || j["groups"].empty()) return fail(r.where("groups") + " must be a non-empty array");
  std::set<std::string> groups;
  for (std::size_t i = 0; i < j["groups"].size(); ++i) {
    std::string g;
    AT_TRY_ASSIGN(g, r.nonEmptyString(j["groups"][i], Reader::index("groups", i)));
    if (!groups.insert(g).second) return fail(r.where(Reader::index("groups", i)) + " repeats '" + g + "'");
    p.groups.push_back(g);
  }
  if (j.contains("seed")) {
    long long seed;
    AT_TRY_ASSIGN(seed, r.integer(j["seed"], "seed"));
    if (seed < 0) return fail(r.where("seed") + " must not be negative");
    p.seed = std::uint64_t(seed);
  }
  if (j.contains("t")) {
    AT_TRY_ASSIGN(p.t, r.number(j["t"], "t"));
    if (p.t < 0 || p.t > 1) return fail(r.where("t") + " must lie in 0..1");
  }
  return p;
}

}  // namespace

Result<StudyProtocol> parseStudyProtocol(const std::string& jsonText, const std::string& sourceName) {
  auto document = parseJsonDocument(jsonText, sourceName);
  if (!document) return tl::unexpected(document.error());
  return withPrintableError(readStudyProtocol(*document, sourceName));
}

Result<StudyProtocol> loadStudyProtocol(const std::string& path) {
  // The paper's survey takes 1.5 KB; anything near this is not a study definition.
  constexpr std::size_t kMaxBytes = std::size_t(16) << 20;
  auto text = readRegularFile(path, path, kMaxBytes);
  if (!text) return tl::unexpected(text.error());
  return parseStudyProtocol(*text, path);
}

std::string serialiseStudyProtocol(const StudyProtocol& p) {
  json j;
  j["schema"] = p.schema;
  j["id"] = p.id;
  j["title"] = p.title;
  j["dataset"] = p.dataset;
  j["structures"] = p.structures;
  j["conditions"] = json::array();
  for (const auto& c : p.conditions)
    j["conditions"].push_back({{"id", c.id}, {"label", c.label}, {"preset_suffix", c.presetSuffix}});
  if (!p.presets.empty()) {
    j["presets"] = json::object();
    for (const auto& [structure, ids] : p.presets) j["presets"][structure] = ids;
  }
  j["items"] = json::array();
  for (const auto& it : p.items) j["items"].push_back({{"id", it.id}, {"wording", it.wording}});
  j["scale"] = {{"min", p.scale.min}, {"max", p.scale.max}};
  j["scale"]["anchors"] = json::object();
  for (const auto& [value, text] : p.scale.anchors) j["scale"]["anchors"][std::to_string(value)] = text;
  j["groups"] = p.groups;
  j["seed"] = p.seed;
  j["t"] = p.t;
  return j.dump(2) + "\n";
}

}  // namespace at::quiz
