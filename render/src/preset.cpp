#include "render/preset.h"

#include "core/safe_name.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "render/camera.h"
#include "core/atomic_file.h"
#include "core/json_document.h"
#include "core/printable_text.h"
#include "core/regular_file.h"

namespace at::render {

using nlohmann::json;

const char* toString(RenderMode mode) {
  switch (mode) {
    case RenderMode::Wdt: return "wdt";
    case RenderMode::Bare: return "bare";
    case RenderMode::Unweighted: return "unweighted";
    case RenderMode::Fuzzy: return "fuzzy";
    case RenderMode::Outline: return "outline";
    case RenderMode::Lighting: return "lighting";
  }
  return "wdt";
}

const std::vector<RenderMode>& allRenderModes() {
  static const std::vector<RenderMode> modes{RenderMode::Wdt,   RenderMode::Bare,    RenderMode::Unweighted,
                                             RenderMode::Fuzzy, RenderMode::Outline, RenderMode::Lighting};
  return modes;
}

Result<RenderMode> parseRenderMode(const std::string& text) {
  for (RenderMode m : allRenderModes())
    if (text == toString(m)) return m;
  return fail("unknown mode '" + text + "' (expected wdt, bare, unweighted, fuzzy, outline or lighting)");
}

namespace {

// Presets are a few kilobytes; anything near this is not a preset.
constexpr std::size_t kMaxPresetBytes = std::size_t(16) << 20;

struct FieldError {
  std::string field, problem;
};

// Each reader returns an error message naming the field, or an empty optional on success.
using Check = std::optional<FieldError>;

Check readNumber(const json& j, const std::string& field, double lo, double hi, double& out, const char* range) {
  if (!j.is_number()) return FieldError{field, std::string("must be a number") + range};
  const double v = j.get<double>();
  if (!(v >= lo && v <= hi) || !std::isfinite(v)) return FieldError{field, std::string("must be a number") + range};
  out = v;
  return std::nullopt;
}

Check readFloat(const json& j, const std::string& field, double lo, double hi, float& out, const char* range) {
  double v = 0;
  if (auto e = readNumber(j, field, lo, hi, v, range)) return e;
  out = float(v);
  return std::nullopt;
}

template <std::size_t N>
Check readFloats(const json& j, const std::string& field, double lo, double hi, std::array<float, N>& out,
                 const std::string& what) {
  if (!j.is_array() || j.size() != N) return FieldError{field, "must be " + what};
  for (std::size_t i = 0; i < N; ++i) {
    if (!j[i].is_number()) return FieldError{field, "must be " + what};
    const double v = j[i].get<double>();
    if (!(v >= lo && v <= hi) || !std::isfinite(v)) return FieldError{field, "must be " + what};
    out[i] = float(v);
  }
  return std::nullopt;
}

Check readString(const json& j, const std::string& field, std::string& out) {
  if (!j.is_string() || j.get<std::string>().empty()) return FieldError{field, "must be a non-empty string"};
  out = j.get<std::string>();
  return std::nullopt;
}

Check unknownKeys(const json& obj, const std::string& prefix, const std::set<std::string>& known) {
  for (auto it = obj.begin(); it != obj.end(); ++it)
    if (!known.count(it.key())) return FieldError{prefix + printableText(it.key(), 60), "is not a known field"};
  return std::nullopt;
}

Check readTf(const json& j, const std::string& field, bool distanceAxis, std::vector<TfPoint>& out) {
  if (!j.is_array() || j.empty()) return FieldError{field, "must be a non-empty array of {\"x\", \"rgba\"} points"};
  std::vector<TfPoint> points;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string at = field + "[" + std::to_string(i) + "]";
    const json& p = j[i];
    if (!p.is_object()) return FieldError{at, "must be an object {\"x\": number, \"rgba\": [r,g,b,a]}"};
    if (auto e = unknownKeys(p, at + ".", {"x", "rgba"})) return e;
    if (!p.contains("x")) return FieldError{at + ".x", "is missing"};
    if (!p.contains("rgba")) return FieldError{at + ".rgba", "is missing"};
    TfPoint tp;
    if (distanceAxis) {
      if (auto e = readNumber(p["x"], at + ".x", 0, 1, tp.x, " in 0..1")) return e;
    } else {
      if (auto e = readNumber(p["x"], at + ".x", -32768, 32767, tp.x, " of HU in -32768..32767")) return e;
    }
    if (i > 0 && !(tp.x > points.back().x)) return FieldError{at + ".x", "must be greater than the previous point's x"};
    if (auto e = readFloats(p["rgba"], at + ".rgba", 0, 1, tp.rgba, "4 numbers in 0..1")) return e;
    points.push_back(tp);
  }
  out = std::move(points);
  return std::nullopt;
}

Check readPreset(const json& root, Preset& p) {
  if (!root.is_object()) return FieldError{"(top level)", "must be a JSON object"};
  if (auto e = unknownKeys(root, "", {"schema", "name", "mode", "data_tf", "distance_tf", "alpha", "t",
                                      "highlight_rgb", "lighting", "weight", "structure_opacity", "context_in_front", "surface", "id",
                                      "structure", "view", "clip"}))
    return e;
  if (root.contains("schema")) {
    if (!root["schema"].is_number_integer() || root["schema"].get<long long>() != 1)
      return FieldError{"schema", "must be 1 (the only schema version)"};
  }
  if (root.contains("name"))
    if (auto e = readString(root["name"], "name", p.name)) return e;
  if (root.contains("mode")) {
    if (!root["mode"].is_string()) return FieldError{"mode", "must be one of wdt, bare, unweighted, fuzzy, outline, lighting"};
    auto m = parseRenderMode(root["mode"].get<std::string>());
    if (!m) return FieldError{"mode", "must be one of wdt, bare, unweighted, fuzzy, outline, lighting"};
    p.mode = *m;
  }
  if (root.contains("data_tf"))
    if (auto e = readTf(root["data_tf"], "data_tf", false, p.dataTf)) return e;
  if (root.contains("distance_tf"))
    if (auto e = readTf(root["distance_tf"], "distance_tf", true, p.distanceTf)) return e;
  if (root.contains("alpha")) {
    if (auto e = readFloat(root["alpha"], "alpha", 1.0000001, 1e6, p.alpha, " greater than 1")) return e;
  }
  if (root.contains("t"))
    if (auto e = readFloat(root["t"], "t", 0, 1, p.t, " in 0..1")) return e;
  if (root.contains("highlight_rgb"))
    if (auto e = readFloats(root["highlight_rgb"], "highlight_rgb", 0, 1, p.highlightRgb, "3 numbers in 0..1")) return e;
  if (root.contains("lighting")) {
    const json& l = root["lighting"];
    if (!l.is_object()) return FieldError{"lighting", "must be an object {\"alpha\", \"beta\"}"};
    if (auto e = unknownKeys(l, "lighting.", {"alpha", "beta"})) return e;
    if (l.contains("alpha"))
      if (auto e = readFloat(l["alpha"], "lighting.alpha", 0, 1e6, p.lightingAlpha, " ≥ 0")) return e;
    if (l.contains("beta"))
      if (auto e = readFloat(l["beta"], "lighting.beta", 0, 1e6, p.lightingBeta, " ≥ 0")) return e;
  }
  if (root.contains("weight")) {
    const json& w = root["weight"];
    if (!w.is_object()) return FieldError{"weight", "must be an object {\"rule\", \"hu_window\", \"base\"}"};
    if (auto e = unknownKeys(w, "weight.", {"rule", "hu_window", "base"})) return e;
    if (w.contains("rule")) {
      if (!w["rule"].is_string() || (w["rule"] != "entering" && w["rule"] != "trapezoid"))
        return FieldError{"weight.rule", "must be \"entering\" or \"trapezoid\""};
      p.weightRule = w["rule"].get<std::string>();
    }
    if (w.contains("hu_window")) {
      if (auto e = readFloats(w["hu_window"], "weight.hu_window", -32768, 32767, p.huWindow,
                              "2 numbers of HU, low < high"))
        return e;
      if (!(p.huWindow[0] < p.huWindow[1])) return FieldError{"weight.hu_window", "must be 2 numbers of HU, low < high"};
    }
    if (w.contains("base"))
      if (auto e = readFloat(w["base"], "weight.base", 0, 1e6, p.weightBase, " ≥ 0")) return e;
  }
  if (root.contains("structure_opacity"))
    if (auto e = readFloat(root["structure_opacity"], "structure_opacity", 0, 1, p.structureOpacity, " in 0..1"))
      return e;
  if (root.contains("context_in_front"))
    if (auto e = readFloat(root["context_in_front"], "context_in_front", 0, 1, p.contextInFront, " in 0..1")) return e;
  if (root.contains("surface")) {
    const json& s = root["surface"];
    if (!s.is_object()) return FieldError{"surface", "must be an object {\"gradient_hu\", \"interior\"}"};
    if (auto e = unknownKeys(s, "surface.", {"gradient_hu", "interior"})) return e;
    if (s.contains("gradient_hu")) {
      if (auto e = readFloats(s["gradient_hu"], "surface.gradient_hu", 0, 1e6, p.surfaceGradientHu,
                              "2 numbers of HU per voxel, 0 ≤ low ≤ high"))
        return e;
      if (!(p.surfaceGradientHu[0] <= p.surfaceGradientHu[1]))
        return FieldError{"surface.gradient_hu", "must be 2 numbers of HU per voxel, 0 ≤ low ≤ high"};
    }
    if (s.contains("interior"))
      if (auto e = readFloat(s["interior"], "surface.interior", 0, 1, p.surfaceInterior, " in 0..1")) return e;
  }
  if (root.contains("id")) {
    std::string s;
    if (auto e = readString(root["id"], "id", s)) return e;
    p.id = s;
  }
  if (root.contains("structure")) {
    std::string s;
    if (auto e = readString(root["structure"], "structure", s)) return e;
    p.structure = s;
  }
  if (root.contains("view")) {
    std::string s;
    if (!root["view"].is_string() || !parseNamedView(root["view"].get<std::string>()))
      return FieldError{"view", "must be one of anterior, posterior, lateral_left, lateral_right, superior, inferior"};
    p.view = root["view"].get<std::string>();
  }
  if (root.contains("clip")) {
    std::array<float, 4> c{};
    if (auto e = readFloats(root["clip"], "clip", -1e6, 1e6, c, "4 numbers nx, ny, nz, d with a non-zero normal"))
      return e;
    if (c[0] == 0 && c[1] == 0 && c[2] == 0)
      return FieldError{"clip", "must be 4 numbers nx, ny, nz, d with a non-zero normal"};
    p.clip = c;
  }
  return std::nullopt;
}

json tfToJson(const std::vector<TfPoint>& tf) {
  json a = json::array();
  for (const TfPoint& p : tf) a.push_back({{"x", p.x}, {"rgba", {p.rgba[0], p.rgba[1], p.rgba[2], p.rgba[3]}}});
  return a;
}

}  // namespace

Result<Preset> parsePreset(const std::string& jsonText, const std::string& source) {
  auto root = parseJsonDocument(jsonText, source);
  if (!root) return tl::unexpected(root.error());
  Preset p;
  if (auto e = readPreset(*root, p)) return tl::unexpected(printableError(Error{ErrorKind::Invalid, source + ": field '" + e->field + "' " + e->problem}));
  return p;
}

Result<Preset> loadPreset(const std::filesystem::path& path) {
  auto text = readRegularFile(path.string(), path.string(), kMaxPresetBytes);
  if (!text) return tl::unexpected(text.error());
  auto p = parsePreset(*text, path.string());
  if (p && !p->id) p->id = path.stem().string();
  return p;
}

std::string presetToJson(const Preset& p) {
  json j;
  j["schema"] = p.schema;
  j["name"] = p.name;
  j["mode"] = toString(p.mode);
  j["data_tf"] = tfToJson(p.dataTf);
  j["distance_tf"] = tfToJson(p.distanceTf);
  j["alpha"] = p.alpha;
  j["t"] = p.t;
  j["highlight_rgb"] = {p.highlightRgb[0], p.highlightRgb[1], p.highlightRgb[2]};
  j["lighting"] = {{"alpha", p.lightingAlpha}, {"beta", p.lightingBeta}};
  j["weight"] = {{"rule", p.weightRule}, {"hu_window", {p.huWindow[0], p.huWindow[1]}}, {"base", p.weightBase}};
  j["structure_opacity"] = p.structureOpacity;
  j["context_in_front"] = p.contextInFront;
  j["surface"] = {{"gradient_hu", {p.surfaceGradientHu[0], p.surfaceGradientHu[1]}}, {"interior", p.surfaceInterior}};
  if (p.id) j["id"] = *p.id;
  if (p.structure) j["structure"] = *p.structure;
  if (p.view) j["view"] = *p.view;
  if (p.clip) j["clip"] = {(*p.clip)[0], (*p.clip)[1], (*p.clip)[2], (*p.clip)[3]};
  return j.dump(2) + "\n";
}

Status savePreset(const Preset& preset, const std::filesystem::path& path) {
  return writeFileAtomically(path.string(), presetToJson(preset));
}

Result<std::vector<std::string>> PresetLibrary::list() const {
  std::error_code ec;
  std::vector<std::string> ids;
  for (std::filesystem::directory_iterator it(dir_, ec), end; !ec && it != end; it.increment(ec))
    if (it->path().extension() == ".json") ids.push_back(it->path().stem().string());
  if (ec) return fail(dir_.string() + ": cannot list presets (" + ec.message() + ")");
  std::sort(ids.begin(), ids.end());
  return ids;
}

Result<Preset> PresetLibrary::load(const std::string& id) const {
  // Ids come from courses (outside text): only a safe name is a file of the library, so a course's
  // "<course>/<id>" preset or "../x" never reads a file.
  if (!isSafeName(id)) return fail(ErrorKind::NotFound, "no preset '" + printableText(id, 80) + "' in " + dir_.string());
  const std::filesystem::path path = dir_ / (id + ".json");
  if (!std::filesystem::exists(path)) return fail("no preset '" + id + "' in " + dir_.string());
  return loadPreset(path);
}

Result<Preset> PresetLibrary::forStructure(const std::string& structureId, RenderMode mode) const {
  const std::string specific = structureId + "_" + toString(mode);
  if (std::filesystem::exists(dir_ / (specific + ".json"))) return load(specific);
  const std::string generic = std::string("default_") + toString(mode);
  if (std::filesystem::exists(dir_ / (generic + ".json"))) return load(generic);
  return fail("no preset '" + specific + "' or '" + generic + "' in " + dir_.string());
}

}  // namespace at::render
