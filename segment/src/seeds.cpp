// The seeds file (segment/seeds.h): strict parsing, writing, and rasterisation onto a grid.
#include "segment/seeds.h"

#include "core/printable_text.h"
#include "core/regular_file.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace at::segment {

namespace {

using nlohmann::json;

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f", v);
  return buf;
}

// Errors of one field: "<source>: <field> <problem>".
struct Reader {
  std::string source;
  tl::unexpected<Error> error(const std::string& field, const std::string& problem) const {
    return fail(source + ": " + field + " " + problem);
  }
  Status onlyKeys(const json& object, const std::string& field, std::initializer_list<const char*> keys) const {
    for (const auto& item : object.items()) {
      // Not a structured binding: clang 14 (the fuzz build) cannot capture one in a lambda.
      const std::string& key = item.key();
      if (std::none_of(keys.begin(), keys.end(), [&](const char* k) { return key == k; }))
        return error(field.empty() ? "field '" + key + "'" : field + "." + key, "is not a known field");
    }
    return {};
  }
  Result<Vec3> point(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 3 || !std::all_of(j.begin(), j.end(), [](const json& v) { return v.is_number(); }))
      return error(field, "must be 3 numbers [x, y, z] in mm");
    const Vec3 p{j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return error(field, "must be finite");
    return p;
  }
  Result<std::array<double, 2>> range(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number() || !(j[0].get<double>() < j[1].get<double>()))
      return error(field, "must be 2 numbers [low, high] with low < high");
    return std::array<double, 2>{j[0].get<double>(), j[1].get<double>()};
  }
};

}  // namespace

namespace {

Result<SeedSet> readSeeds(const std::string& jsonText, const std::string& source) {
  const Reader r{source};
  json doc;
  try {
    doc = json::parse(jsonText);
  } catch (const json::exception& e) {
    std::string what = e.what();
    std::replace(what.begin(), what.end(), '\n', ' ');
    return fail(source + ": not valid JSON (" + what + ")");
  }
  if (!doc.is_object()) return fail(source + ": expected a JSON object with \"labels\" and \"strokes\"");
  if (auto ok = r.onlyKeys(doc, "", {"schema", "space", "labels", "strokes", "grow"}); !ok) return tl::unexpected(ok.error());
  if (doc.contains("schema") && (!doc["schema"].is_number_integer() || doc["schema"].get<int>() != 1))
    return r.error("schema", "must be 1");
  bool ras = false;
  if (doc.contains("space")) {
    const json& space = doc["space"];
    if (!space.is_string() || (space != "LPS" && space != "RAS")) return r.error("space", "must be \"LPS\" or \"RAS\"");
    ras = space == "RAS";
  }
  SeedSet set;
  if (!doc.contains("labels") || !doc["labels"].is_array() || doc["labels"].empty())
    return r.error("labels", "must be a non-empty list of {\"value\": N, \"name\": \"…\"}");
  std::set<int> values;
  std::set<std::string> names;
  for (std::size_t i = 0; i < doc["labels"].size(); ++i) {
    const json& j = doc["labels"][i];
    const std::string field = "labels[" + std::to_string(i) + "]";
    if (!j.is_object()) return r.error(field, "must be an object");
    if (auto ok = r.onlyKeys(j, field, {"value", "name", "colour", "range", "min_diameter_mm", "grow_range"}); !ok)
      return tl::unexpected(ok.error());
    SeedLabel label;
    if (!j.contains("value") || !j["value"].is_number_integer() || j["value"].get<long long>() < 0 ||
        j["value"].get<long long>() > 65534)
      return r.error(field + ".value", "must be a label value 0 … 65534");
    label.value = std::uint16_t(j["value"].get<int>());
    if (!j.contains("name") || !j["name"].is_string() || j["name"].get<std::string>().empty())
      return r.error(field + ".name", "must be a non-empty string");
    label.name = j["name"].get<std::string>();
    if (!values.insert(label.value).second) return r.error(field + ".value", std::to_string(label.value) + " is listed twice");
    if (!names.insert(label.name).second) return r.error(field + ".name", "'" + label.name + "' is listed twice");
    if (j.contains("colour")) {
      const json& c = j["colour"];
      if (!c.is_array() || c.size() != 3 ||
          !std::all_of(c.begin(), c.end(), [](const json& v) { return v.is_number() && v.get<double>() >= 0 && v.get<double>() <= 1; }))
        return r.error(field + ".colour", "must be 3 numbers in 0..1");
      label.colour = std::array<float, 3>{c[0].get<float>(), c[1].get<float>(), c[2].get<float>()};
    }
    if (j.contains("range")) {
      auto range = r.range(j["range"], field + ".range");
      if (!range) return tl::unexpected(range.error());
      label.range = *range;
    }
    if (j.contains("min_diameter_mm")) {
      if (!j["min_diameter_mm"].is_number() || !(j["min_diameter_mm"].get<double>() >= 0))
        return r.error(field + ".min_diameter_mm", "must be a number >= 0");
      label.minDiameterMm = j["min_diameter_mm"].get<double>();
    }
    if (j.contains("grow_range")) {
      if (j["grow_range"] == "bone") {
        label.growRangeBone = true;
      } else {
        auto range = r.range(j["grow_range"], field + ".grow_range");
        if (!range) return r.error(field + ".grow_range", "must be \"bone\" or 2 numbers [low, high] with low < high");
        label.growRange = *range;
      }
      if (label.value == 0) return r.error(field + ".grow_range", "the background (value 0) cannot have one");
    }
    set.labels.push_back(std::move(label));
  }
  const auto labelNames = [&] {
    std::string all;
    for (const SeedLabel& l : set.labels) all += (all.empty() ? "" : ", ") + l.name;
    return all;
  };
  if (!doc.contains("strokes") || !doc["strokes"].is_array())
    return r.error("strokes", "must be a list of {\"label\": …, \"points\": [[x, y, z], …]}");
  for (std::size_t i = 0; i < doc["strokes"].size(); ++i) {
    const json& j = doc["strokes"][i];
    const std::string field = "strokes[" + std::to_string(i) + "]";
    if (!j.is_object()) return r.error(field, "must be an object");
    if (auto ok = r.onlyKeys(j, field, {"label", "points", "radius_mm"}); !ok) return tl::unexpected(ok.error());
    SeedStroke stroke;
    if (!j.contains("label")) return r.error(field + ".label", "is missing (a label's name or value)");
    const json& ref = j["label"];
    const auto it = std::find_if(set.labels.begin(), set.labels.end(), [&](const SeedLabel& l) {
      return (ref.is_string() && l.name == ref.get<std::string>()) ||
             (ref.is_number_integer() && ref.get<long long>() == l.value);
    });
    if (it == set.labels.end())
      return r.error(field + ".label", (ref.is_string() ? "'" + ref.get<std::string>() + "'" : ref.dump()) +
                                           " is not one of the labels (" + labelNames() + ")");
    stroke.label = std::size_t(it - set.labels.begin());
    if (!j.contains("points") || !j["points"].is_array() || j["points"].empty())
      return r.error(field + ".points", "must be a non-empty list of [x, y, z] points in mm");
    for (std::size_t p = 0; p < j["points"].size(); ++p) {
      auto point = r.point(j["points"][p], field + ".points[" + std::to_string(p) + "]");
      if (!point) return tl::unexpected(point.error());
      if (ras) (*point)[0] = -(*point)[0], (*point)[1] = -(*point)[1];
      stroke.pointsMm.push_back(*point);
    }
    if (j.contains("radius_mm")) {
      if (!j["radius_mm"].is_number() || !(j["radius_mm"].get<double>() >= 0) || j["radius_mm"].get<double>() > 100)
        return r.error(field + ".radius_mm", "must be a number 0 … 100");
      stroke.radiusMm = j["radius_mm"].get<double>();
    }
    set.strokes.push_back(std::move(stroke));
  }
  if (doc.contains("grow")) {
    const json& g = doc["grow"];
    if (!g.is_object()) return r.error("grow", "must be an object");
    if (auto ok = r.onlyKeys(g, "grow", {"weight", "window", "base", "range", "smoothing"}); !ok) return tl::unexpected(ok.error());
    if (g.contains("weight")) {
      if (!g["weight"].is_string()) return r.error("grow.weight", "must be a string");
      set.grow.weight = g["weight"].get<std::string>();
    }
    if (g.contains("window")) {
      auto window = r.range(g["window"], "grow.window");
      if (!window) return tl::unexpected(window.error());
      set.grow.window = *window;
    }
    if (g.contains("base")) {
      if (!g["base"].is_number() || !(g["base"].get<double>() > 0)) return r.error("grow.base", "must be a number > 0");
      set.grow.base = g["base"].get<double>();
    }
    if (g.contains("smoothing")) {
      const json& v = g["smoothing"];
      if (!v.is_number() || !(v.get<double>() >= 0 && v.get<double>() <= 8))
        return r.error("grow.smoothing", "must be a number of voxels 0 … 8");
      set.grow.smoothing = v.get<double>();
    }
    if (g.contains("range")) {
      auto range = r.range(g["range"], "grow.range");
      if (!range) return tl::unexpected(range.error());
      set.grow.range = *range;
    }
  }
  return set;
}

}  // namespace

// Label names and keys quoted from the file may hold any bytes.
Result<SeedSet> parseSeeds(const std::string& jsonText, const std::string& source) {
  return withPrintableError(readSeeds(jsonText, source));
}

Result<SeedSet> loadSeeds(const std::filesystem::path& path) {
  // A seeds file of a hundred thousand dots is a few MB; a FIFO or device is refused, never read.
  auto text = readRegularFile(path.string(), path.string(), std::size_t(64) << 20);
  if (!text) return tl::unexpected(text.error());
  return parseSeeds(*text, path.string());
}

std::string seedsToJson(const SeedSet& seeds) {
  // One label and one stroke a line: files of thousands of dots stay readable and small.
  std::string out = "{\n  \"schema\": 1,\n  \"space\": \"LPS\",\n  \"labels\": [\n";
  for (std::size_t i = 0; i < seeds.labels.size(); ++i) {
    const SeedLabel& l = seeds.labels[i];
    json j{{"value", l.value}, {"name", l.name}};
    if (l.colour) j["colour"] = *l.colour;
    if (l.range) j["range"] = *l.range;
    if (l.minDiameterMm > 0) j["min_diameter_mm"] = l.minDiameterMm;
    if (l.growRangeBone) j["grow_range"] = "bone";
    else if (l.growRange) j["grow_range"] = *l.growRange;
    out += "    " + j.dump() + (i + 1 < seeds.labels.size() ? ",\n" : "\n");
  }
  out += "  ],\n  \"strokes\": [\n";
  for (std::size_t i = 0; i < seeds.strokes.size(); ++i) {
    const SeedStroke& s = seeds.strokes[i];
    json points = json::array();
    for (const Vec3& p : s.pointsMm) points.push_back({std::round(p[0] * 1000) / 1000, std::round(p[1] * 1000) / 1000,
                                                       std::round(p[2] * 1000) / 1000});
    json j{{"label", seeds.labels.at(s.label).name}, {"radius_mm", s.radiusMm}, {"points", points}};
    out += "    " + j.dump() + (i + 1 < seeds.strokes.size() ? ",\n" : "\n");
  }
  out += "  ]";
  json grow = json::object();
  if (seeds.grow.weight) grow["weight"] = *seeds.grow.weight;
  if (seeds.grow.window) grow["window"] = *seeds.grow.window;
  if (seeds.grow.base) grow["base"] = *seeds.grow.base;
  if (seeds.grow.range) grow["range"] = *seeds.grow.range;
  if (seeds.grow.smoothing) grow["smoothing"] = *seeds.grow.smoothing;
  if (!grow.empty()) out += ",\n  \"grow\": " + grow.dump();
  return out + "\n}\n";
}

std::size_t seedVisitBudget(const Dims& dims) { return std::max(dims.count(), kMinSeedVisitBudget); }

Result<RasterisedSeeds> rasteriseSeeds(const SeedSet& seeds, const Geometry& grid) {
  const Dims d = grid.dims;
  const double step = 0.5 * std::min({grid.spacingMm[0], grid.spacingMm[1], grid.spacingMm[2]});
  const auto extent = [&] {
    const Vec3 a = grid.indexToPatient({-0.5, -0.5, -0.5}), b = grid.indexToPatient({d.x - 0.5, d.y - 0.5, d.z - 0.5});
    return "x " + number(std::min(a[0], b[0])) + " … " + number(std::max(a[0], b[0])) + ", y " +
           number(std::min(a[1], b[1])) + " … " + number(std::max(a[1], b[1])) + ", z " + number(std::min(a[2], b[2])) +
           " … " + number(std::max(a[2], b[2])) + " mm LPS";
  };
  for (std::size_t s = 0; s < seeds.strokes.size(); ++s) {
    const SeedStroke& stroke = seeds.strokes[s];
    for (std::size_t p = 0; p < stroke.pointsMm.size(); ++p) {
      // Tested in continuous index space, before any cast: a point millions of mm away has an
      // index no int holds (casting it is undefined behaviour, and it could wrap onto the grid).
      const Vec3 ijk = grid.patientToIndex(stroke.pointsMm[p]);
      const auto inside = [](double index, int size) { return index > -0.5 && index < size - 0.5; };
      if (!inside(ijk[0], d.x) || !inside(ijk[1], d.y) || !inside(ijk[2], d.z))
        return fail("seeds: strokes[" + std::to_string(s) + "].points[" + std::to_string(p) + "] (" +
                    number(stroke.pointsMm[p][0]) + ", " + number(stroke.pointsMm[p][1]) + ", " +
                    number(stroke.pointsMm[p][2]) + ") mm of label '" + printableText(seeds.labels[stroke.label].name) +
                    "' lies outside the volume (" + extent() + ")");
      if (!std::isfinite(stroke.radiusMm)) return fail("seeds: strokes[" + std::to_string(s) + "].radius_mm is not finite");
    }
  }

  // Every dot of every stroke (the points, and samples every half voxel between them) visits the
  // voxels of its radius' box, clipped to the grid. `visit(stroke, centre, box)` returns false to stop.
  struct Box {
    int lo[3], hi[3];
    int centre[3];
    std::size_t count() const {
      return std::size_t(hi[0] - lo[0] + 1) * std::size_t(hi[1] - lo[1] + 1) * std::size_t(hi[2] - lo[2] + 1);
    }
  };
  const auto forEachDot = [&](const auto& visit) {
    for (std::size_t s = 0; s < seeds.strokes.size(); ++s) {
      const SeedStroke& stroke = seeds.strokes[s];
      int reach[3] = {0, 0, 0};
      if (stroke.radiusMm > 0)
        for (int a = 0; a < 3; ++a) {
          const double r = std::ceil(stroke.radiusMm / grid.spacingMm[std::size_t(a)]) + 1;
          reach[a] = int(std::min(r, double(std::max({d.x, d.y, d.z}))));
        }
      const int size[3] = {d.x, d.y, d.z};
      const auto dot = [&](const Vec3& centreMm) {
        const Vec3 c = grid.patientToIndex(centreMm);
        Box box;
        for (int a = 0; a < 3; ++a) {
          box.centre[a] = std::clamp(int(std::lround(c[std::size_t(a)])), 0, size[a] - 1);
          box.lo[a] = std::max(0, box.centre[a] - reach[a]);
          box.hi[a] = std::min(size[a] - 1, box.centre[a] + reach[a]);
        }
        return visit(stroke, centreMm, box);
      };
      if (!dot(stroke.pointsMm.front())) return;
      for (std::size_t p = 1; p < stroke.pointsMm.size(); ++p) {
        const Vec3 a = stroke.pointsMm[p - 1], b = stroke.pointsMm[p];
        const int samples = std::max(1, int(std::ceil(norm(b - a) / step)));
        for (int t = 1; t <= samples; ++t)
          if (!dot(a + (double(t) / samples) * (b - a))) return;
      }
    }
  };

  // First the work is counted (stopping as soon as it is over the budget), so that a small file of
  // large radii is refused at once instead of running for minutes.
  const std::size_t budget = seedVisitBudget(d);
  std::size_t visits = 0;
  int lo[3] = {d.x, d.y, d.z}, hi[3] = {-1, -1, -1};
  forEachDot([&](const SeedStroke&, const Vec3&, const Box& box) {
    visits += box.count();
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], box.lo[a]), hi[a] = std::max(hi[a], box.hi[a]);
    return visits <= budget;
  });
  if (visits > budget)
    return fail("seeds: the strokes' dots would visit more than " + std::to_string(budget) +
                " voxels (this volume's voxel count), a limit set against runaway work; use a smaller radius_mm "
                "or fewer points");

  // Then painted into the box they cover: each voxel keeps the index + 1 of the last stroke label.
  RasterisedSeeds out;
  out.perLabel.assign(seeds.labels.size(), 0);
  if (hi[0] < 0) return out;
  const int bx = hi[0] - lo[0] + 1, by = hi[1] - lo[1] + 1, bz = hi[2] - lo[2] + 1;
  std::vector<std::uint32_t> painted(std::size_t(bx) * std::size_t(by) * std::size_t(bz), 0);
  const auto at = [&](int i, int j, int k) -> std::uint32_t& {
    return painted[std::size_t(i - lo[0]) + std::size_t(bx) * (std::size_t(j - lo[1]) + std::size_t(by) * std::size_t(k - lo[2]))];
  };
  forEachDot([&](const SeedStroke& stroke, const Vec3& centreMm, const Box& box) {
    const std::uint32_t value = std::uint32_t(stroke.label) + 1;
    at(box.centre[0], box.centre[1], box.centre[2]) = value;  // the nearest voxel in any case
    if (stroke.radiusMm <= 0) return true;
    for (int k = box.lo[2]; k <= box.hi[2]; ++k)
      for (int j = box.lo[1]; j <= box.hi[1]; ++j)
        for (int i = box.lo[0]; i <= box.hi[0]; ++i)
          if (norm(grid.indexToPatient({double(i), double(j), double(k)}) - centreMm) <= stroke.radiusMm) at(i, j, k) = value;
    return true;
  });
  for (int k = lo[2]; k <= hi[2]; ++k)
    for (int j = lo[1]; j <= hi[1]; ++j)
      for (int i = lo[0]; i <= hi[0]; ++i)
        if (const std::uint32_t v = at(i, j, k)) {
          out.seeds.push_back({d.index(i, j, k), seeds.labels[v - 1].value});
          ++out.perLabel[v - 1];
        }
  return out;
}

Status requireTwoSeededLabels(const SeedSet& seeds, const RasterisedSeeds& raster) {
  std::vector<std::string> seeded;
  for (std::size_t i = 0; i < seeds.labels.size(); ++i)
    if (raster.perLabel[i] > 0) seeded.push_back(seeds.labels[i].name);
  if (seeded.size() >= 2) return {};
  if (seeded.empty()) return fail("seeds: no label has a stroke; grow from seeds needs strokes of two or more labels");
  return fail("seeds: only label '" + printableText(seeded.front()) +
              "' has strokes; grow from seeds needs two or more labels (add strokes of the background or of a "
              "neighbouring structure)");
}

}  // namespace at::segment
