// manifest.json and dataset/structures.json: strict readers (unknown fields, wrong types and
// out-of-range values are errors naming the field) and their writers.
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include <nlohmann/json.hpp>

#include "package/course_package.h"
#include "core/printable_text.h"
#include "core/safe_name.h"
#include "volume/structure_forms.h"

namespace at::package {

namespace {

using json = nlohmann::json;

// Parses without exceptions escaping: malformed text and numbers out of range are errors.
Result<json> parseJson(std::string_view text, const std::string& source) {
  try {
    return json::parse(text.begin(), text.end());
  } catch (const json::exception& e) {
    return fail(source + ": not valid JSON (" + std::string(e.what()) + ")");
  }
}

// One JSON object read strictly, errors prefixed with "<source>: <path>".
class Fields {
 public:
  Fields(const json& j, std::string source, std::string path) : j_(j), source_(std::move(source)), path_(std::move(path)) {}

  Status expect(std::initializer_list<const char*> allowed) const {
    if (!j_.is_object()) return fail(where("") + "must be an object");
    for (const auto& item : j_.items())
      if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return item.key() == a; }))
        return fail(where(item.key()) + "unknown field");
    return {};
  }
  bool has(const char* key) const { return j_.contains(key); }
  const json& raw(const char* key) const { return j_.at(key); }
  std::string field(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  std::string where(const std::string& key) const {
    const std::string f = key.empty() ? path_ : field(key);
    return source_ + ": " + (f.empty() ? "" : f + ": ");
  }

  Result<std::string> text(const char* key, bool required, bool nonEmpty = true) const {
    if (!j_.contains(key)) {
      if (required) return fail(where(key) + "missing");
      return std::string();
    }
    if (!j_[key].is_string()) return fail(where(key) + "must be a string");
    std::string value = j_[key].get<std::string>();
    if (required && nonEmpty && value.empty()) return fail(where(key) + "must not be empty");
    return value;
  }
  Result<std::int64_t> integer(const char* key, std::int64_t lo, std::int64_t hi) const {
    if (!j_.contains(key)) return fail(where(key) + "missing");
    const json& v = j_[key];
    if (!v.is_number_integer()) return fail(where(key) + "must be an integer");
    if (v.is_number_unsigned() && v.get<std::uint64_t>() > std::uint64_t(hi))
      return fail(where(key) + "must be " + std::to_string(lo) + ".." + std::to_string(hi));
    const std::int64_t n = v.get<std::int64_t>();
    if (n < lo || n > hi) return fail(where(key) + "must be " + std::to_string(lo) + ".." + std::to_string(hi));
    return n;
  }
  Result<double> number(const char* key) const {
    if (!j_.contains(key)) return fail(where(key) + "missing");
    const json& v = j_[key];
    if (!v.is_number() || !std::isfinite(v.get<double>())) return fail(where(key) + "must be a finite number");
    return v.get<double>();
  }
  Result<std::vector<double>> numbers(const char* key, std::size_t count) const {
    if (!j_.contains(key)) return fail(where(key) + "missing");
    const json& v = j_[key];
    if (!v.is_array() || v.size() != count) return fail(where(key) + "must be " + std::to_string(count) + " numbers");
    std::vector<double> out;
    for (const json& x : v) {
      if (!x.is_number() || !std::isfinite(x.get<double>())) return fail(where(key) + "must be " + std::to_string(count) + " finite numbers");
      out.push_back(x.get<double>());
    }
    return out;
  }

 private:
  const json& j_;
  std::string source_, path_;
};

#define AT_TAKE(var, expr)                                        \
  auto var##_taken = (expr);                                      \
  if (!var##_taken) return tl::unexpected(var##_taken.error());   \
  auto var = std::move(*var##_taken)

bool isSha256Hex(const std::string& s) {
  return s.size() == 64 && std::all_of(s.begin(), s.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

bool isChecksum(const std::string& s) { return s.size() == 71 && s.rfind("sha256:", 0) == 0 && isSha256Hex(s.substr(7)); }

json geometryJson(const Geometry& g) {
  json direction = json::array();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) direction.push_back(g.direction.m[std::size_t(r)][std::size_t(c)]);
  return {{"dims", {g.dims.x, g.dims.y, g.dims.z}},
          {"spacing_mm", g.spacingMm},
          {"origin_mm", g.originMm},
          {"direction", direction}};
}

Result<Geometry> readGeometry(const json& j, const std::string& source, const std::string& path) {
  Fields f(j, source, path);
  if (auto ok = f.expect({"dims", "spacing_mm", "origin_mm", "direction"}); !ok) return tl::unexpected(ok.error());
  AT_TAKE(dims, f.numbers("dims", 3));
  AT_TAKE(spacing, f.numbers("spacing_mm", 3));
  AT_TAKE(origin, f.numbers("origin_mm", 3));
  AT_TAKE(direction, f.numbers("direction", 9));
  Geometry g;
  for (double d : dims)
    if (d < 1 || d > 100000 || d != std::floor(d)) return fail(f.where("dims") + "must be 3 whole numbers 1..100000");
  g.dims = {int(dims[0]), int(dims[1]), int(dims[2])};
  for (int i = 0; i < 3; ++i) {
    if (!(spacing[std::size_t(i)] > 0)) return fail(f.where("spacing_mm") + "must be 3 numbers > 0");
    g.spacingMm[std::size_t(i)] = spacing[std::size_t(i)];
    g.originMm[std::size_t(i)] = origin[std::size_t(i)];
  }
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) g.direction.m[std::size_t(r)][std::size_t(c)] = direction[std::size_t(r * 3 + c)];
  if (!(std::fabs(g.direction.determinant()) > 0.5)) return fail(f.where("direction") + "must hold 3 independent unit axes");
  return g;
}

json readingJson(const VolumeReading& r) {
  json j = {{"intensity", intensityChoiceName(r.intensity)}};
  if (r.intercept) j["intercept"] = *r.intercept;
  if (r.slope) j["slope"] = *r.slope;
  if (r.skipUnreadableFiles) j["skip_unreadable"] = true;
  if (!r.modality.empty()) j["modality"] = r.modality;
  return j;
}

// Held to the bounds of a user's --intercept and --slope (checkRescale, volume/intensity.h).
Result<VolumeReading> readReading(const json& j, const std::string& source, const std::string& path) {
  Fields f(j, source, path);
  if (auto ok = f.expect({"intensity", "intercept", "slope", "skip_unreadable", "modality"}); !ok) return tl::unexpected(ok.error());
  AT_TAKE(intensity, f.text("intensity", true));
  auto choice = parseIntensityChoice(intensity);
  if (!choice) return fail(f.where("intensity") + "must be auto, hu or plain, not '" + intensity + "'");
  VolumeReading r;
  r.intensity = *choice;
  if (f.has("intercept")) {
    AT_TAKE(intercept, f.number("intercept"));
    if (!checkRescale(intercept, 1)) return fail(f.where("intercept") + "must be a number within ±" + kRescaleInterceptLimitText);
    r.intercept = intercept;
  }
  if (f.has("slope")) {
    AT_TAKE(slope, f.number("slope"));
    if (!checkRescale(0, slope)) return fail(f.where("slope") + "must be a number other than 0 within ±" + kRescaleSlopeLimitText);
    r.slope = slope;
  }
  if (f.has("skip_unreadable")) {
    if (!f.raw("skip_unreadable").is_boolean()) return fail(f.where("skip_unreadable") + "must be true or false");
    r.skipUnreadableFiles = f.raw("skip_unreadable").get<bool>();
  }
  if (f.has("modality")) {
    AT_TAKE(modality, f.text("modality", true));
    if (!isDicomModalityCode(modality))
      return fail(f.where("modality") + "must be a DICOM modality code (up to 16 of A-Z, 0-9, '_' and ' '), not '" +
                  modality + "'");
    r.modality = modality;
  }
  return r;
}

Result<DatasetEntry> readDataset(const json& j, const std::string& source) {
  Fields f(j, source, "dataset");
  if (auto ok = f.expect({"name", "source", "species", "geometry", "source_volume_checksum", "source_labels_checksum",
                          "reference", "reading"});
      !ok)
    return tl::unexpected(ok.error());
  DatasetEntry d;
  AT_TAKE(name, f.text("name", true));
  AT_TAKE(kind, f.text("source", true));
  AT_TAKE(species, f.text("species", false));
  d.name = name;
  if (!species.empty()) d.species = species;
  if (!isValidSpecies(d.species))
    return fail(f.where("species") + "'" + printableText(d.species, 40) + "' is not a species name (lower-case letters, '-', '_')");
  if (kind == "builtin") d.source = VolumeSource::Builtin;
  else if (kind == "included") d.source = VolumeSource::Included;
  else if (kind == "reference") d.source = VolumeSource::Reference;
  else return fail(f.where("source") + "must be builtin, included or reference, not '" + kind + "'");
  const bool builtin = d.source == VolumeSource::Builtin;
  // A package's own dataset becomes a folder of the data folder: one safe name (core/safe_name.h).
  // A built-in's name ("phantom:64") is checked against the built-in names by the importer.
  if (!builtin)
    if (auto ok = checkSafeName(source + ": " + f.field("name"), name); !ok) return tl::unexpected(ok.error());
  for (const char* key : {"geometry", "source_volume_checksum"})
    if (builtin == f.has(key))
      return fail(f.where(key) + (builtin ? "not allowed for a built-in dataset" : "missing"));
  if (!builtin) {
    AT_TAKE(geometry, readGeometry(f.raw("geometry"), source, f.field("geometry")));
    d.geometry = geometry;
    AT_TAKE(volumeSum, f.text("source_volume_checksum", true));
    if (!isChecksum(volumeSum)) return fail(f.where("source_volume_checksum") + "must be sha256: and 64 hex digits");
    d.sourceVolumeChecksum = volumeSum;
  }
  AT_TAKE(labelsSum, f.text("source_labels_checksum", false));
  if (!labelsSum.empty() && !isChecksum(labelsSum))
    return fail(f.where("source_labels_checksum") + "must be sha256: and 64 hex digits");
  d.sourceLabelsChecksum = labelsSum;
  if ((d.source == VolumeSource::Reference) != f.has("reference"))
    return fail(f.where("reference") + (f.has("reference") ? "only for a referenced volume" : "missing"));
  if (f.has("reading")) {
    if (builtin) return fail(f.where("reading") + "not allowed for a built-in dataset");
    AT_TAKE(reading, readReading(f.raw("reading"), source, f.field("reading")));
    d.reading = reading;
  }
  if (f.has("reference")) {
    Fields r(f.raw("reference"), source, f.field("reference"));
    if (auto ok = r.expect({"file_name", "note"}); !ok) return tl::unexpected(ok.error());
    AT_TAKE(fileName, r.text("file_name", true));
    AT_TAKE(note, r.text("note", false));
    d.referenceFileName = fileName;
    d.referenceNote = note;
  }
  return d;
}

}  // namespace

const char* toString(VolumeSource source) {
  switch (source) {
    case VolumeSource::Builtin: return "builtin";
    case VolumeSource::Included: return "included";
    case VolumeSource::Reference: return "reference";
  }
  return "?";
}

const PackagedFile* Manifest::find(const std::string& path) const {
  for (const PackagedFile& f : files)
    if (f.path == path) return &f;
  return nullptr;
}

bool safeEntryName(std::string_view name) {
  if (name.empty() || name.size() > 200) return false;
  std::size_t start = 0;
  while (start <= name.size()) {
    const std::size_t end = std::min(name.find('/', start), name.size());
    const std::string_view part = name.substr(start, end - start);
    if (part.empty() || part.front() == '.') return false;  // "", ".", ".." and hidden names
    for (char c : part)
      if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-' || c == '.'))
        return false;
    start = end + 1;
  }
  return true;
}

std::string manifestToJson(const Manifest& m) {
  json dataset = {{"name", m.dataset.name}, {"source", toString(m.dataset.source)}, {"species", m.dataset.species}};
  if (m.dataset.geometry) dataset["geometry"] = geometryJson(*m.dataset.geometry);
  if (!m.dataset.sourceVolumeChecksum.empty()) dataset["source_volume_checksum"] = m.dataset.sourceVolumeChecksum;
  if (!m.dataset.sourceLabelsChecksum.empty()) dataset["source_labels_checksum"] = m.dataset.sourceLabelsChecksum;
  if (m.dataset.source == VolumeSource::Reference)
    dataset["reference"] = {{"file_name", m.dataset.referenceFileName}, {"note", m.dataset.referenceNote}};
  if (m.dataset.reading) dataset["reading"] = readingJson(*m.dataset.reading);
  json files = json::array();
  for (const PackagedFile& f : m.files) files.push_back({{"path", f.path}, {"size", f.size}, {"sha256", f.sha256}});
  const json j = {{"format", kFormatName},
                  {"format_version", m.formatVersion},
                  {"created_by", m.createdBy},
                  {"course", {{"id", m.courseId}, {"version", m.courseVersion}, {"title", m.courseTitle}}},
                  {"dataset", dataset},
                  {"files", files}};
  return j.dump(2) + "\n";
}

Result<Manifest> parseManifest(std::string_view text, const std::string& source) {
  AT_TAKE(j, parseJson(text, source));
  Fields f(j, source, "");
  // The format and its version first: a newer package says so before any field it may have added.
  if (!j.is_object()) return fail(source + ": must be a JSON object");
  AT_TAKE(format, f.text("format", true));
  if (format != kFormatName) return fail(f.where("format") + "'" + format + "' is not an Anatomy Tutor course package");
  AT_TAKE(version, f.integer("format_version", 1, 1000000));
  if (version > kFormatVersion)
    return fail(ErrorKind::Unavailable, f.where("format_version") + "the package has format version " + std::to_string(version) +
                                            ", newer than this program reads (" + std::to_string(kFormatVersion) +
                                            "): update Anatomy Tutor to import it");
  if (auto ok = f.expect({"format", "format_version", "created_by", "course", "dataset", "files"}); !ok)
    return tl::unexpected(ok.error());
  Manifest m;
  m.formatVersion = int(version);
  AT_TAKE(createdBy, f.text("created_by", false));
  m.createdBy = createdBy;
  if (!f.has("course")) return fail(f.where("course") + "missing");
  Fields c(f.raw("course"), source, "course");
  if (auto ok = c.expect({"id", "version", "title"}); !ok) return tl::unexpected(ok.error());
  AT_TAKE(courseId, c.text("id", true));
  AT_TAKE(courseVersion, c.integer("version", 1, 1000000000));
  AT_TAKE(courseTitle, c.text("title", false));
  // The course id keys the course's presets in the database (app/src/services/course_presets.h).
  if (auto ok = checkSafeName(source + ": " + c.field("id"), courseId); !ok) return tl::unexpected(ok.error());
  m.courseId = courseId;
  m.courseVersion = int(courseVersion);
  m.courseTitle = courseTitle;
  if (!f.has("dataset")) return fail(f.where("dataset") + "missing");
  AT_TAKE(dataset, readDataset(f.raw("dataset"), source));
  m.dataset = dataset;
  if (!f.has("files") || !f.raw("files").is_array()) return fail(f.where("files") + "must be an array");
  std::set<std::string> seen;
  for (std::size_t i = 0; i < f.raw("files").size(); ++i) {
    Fields e(f.raw("files")[i], source, "files[" + std::to_string(i) + "]");
    if (auto ok = e.expect({"path", "size", "sha256"}); !ok) return tl::unexpected(ok.error());
    AT_TAKE(path, e.text("path", true));
    AT_TAKE(size, e.integer("size", 0, std::numeric_limits<std::int64_t>::max()));
    AT_TAKE(sha, e.text("sha256", true));
    if (!safeEntryName(path)) return fail(e.where("path") + "'" + path + "' is not a safe relative name");
    if (path == "manifest.json" || !seen.insert(path).second) return fail(e.where("path") + "'" + path + "' is listed twice");
    if (!isSha256Hex(sha)) return fail(e.where("sha256") + "must be 64 lowercase hex digits");
    m.files.push_back({path, std::uint64_t(size), sha});
  }
  return m;
}

std::string structuresToJson(const std::vector<Structure>& structures) {
  json list = json::array();
  for (const Structure& s : structures)
    list.push_back({{"label", s.label}, {"id", s.id}, {"name", s.displayName}, {"colour", s.colour},
                    {"system", s.system}, {"description", s.description}});
  return list.dump(2) + "\n";
}

Result<std::vector<Structure>> parseStructuresJson(std::string_view text, const std::string& source) {
  AT_TAKE(j, parseJson(text, source));
  if (!j.is_array()) return fail(source + ": must be an array of structures");
  std::vector<Structure> out;
  std::set<int> labels;
  std::set<std::string> ids;
  for (std::size_t i = 0; i < j.size(); ++i) {
    Fields f(j[i], source, "[" + std::to_string(i) + "]");
    if (auto ok = f.expect({"label", "id", "name", "colour", "system", "description"}); !ok) return tl::unexpected(ok.error());
    Structure s;
    AT_TAKE(label, f.integer("label", 1, 65535));
    AT_TAKE(id, f.text("id", true));
    AT_TAKE(name, f.text("name", true));
    AT_TAKE(colour, f.numbers("colour", 3));
    AT_TAKE(system, f.text("system", false));
    AT_TAKE(description, f.text("description", false));
    // The forms an import gives (volume/structure.h): ids that key questions and lessons, names
    // and systems shown on one line of a listing, descriptions with no terminal escapes.
    if (!isValidStructureId(id)) return fail(f.where("id") + "'" + printableText(id, 40) + "' is not a structure id (a-z, 0-9, '_')");
    if (!isPrintableLine(name, 600)) return fail(f.where("name") + "must be one printable line of at most 600 bytes");
    if (!isPrintableLine(system, 600)) return fail(f.where("system") + "must be one printable line of at most 600 bytes");
    if (!isPrintableLines(description, 4000))
      return fail(f.where("description") + "must be printable text (no terminal escapes) of at most 4000 bytes");
    if (!labels.insert(int(label)).second) return fail(f.where("label") + "label " + std::to_string(label) + " is listed twice");
    if (!ids.insert(id).second) return fail(f.where("id") + "'" + id + "' is listed twice");
    for (double c : colour)
      if (c < 0 || c > 1) return fail(f.where("colour") + "must be 3 numbers in 0..1");
    s.label = std::uint16_t(label);
    s.id = id;
    s.displayName = name;
    s.colour = {float(colour[0]), float(colour[1]), float(colour[2])};
    s.system = system;
    s.description = description;
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace at::package
