#include "db/dataset_store.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <tuple>

#include <nlohmann/json.hpp>

#include "database.h"
#include "core/sha256.h"
#include "db/checksum.h"
#include "volume/structure_forms.h"

namespace at::db {

namespace {

constexpr const char* kSelectDataset =
    "SELECT d.id, d.name, d.species, d.volume_path, d.volume_checksum, d.labels_path, d.labels_checksum,"
    " d.names_path, d.dim_x, d.dim_y, d.dim_z, d.spacing_x, d.spacing_y, d.spacing_z,"
    " d.origin_x, d.origin_y, d.origin_z, d.direction, d.orientation, d.created_at,"
    " (SELECT count(*) FROM structures s WHERE s.dataset_id = d.id), d.load_options"
    " FROM datasets d";

// A stored path as a usable one: relative paths (assets in the database's data folder) are
// relative to datasetPathBase (kept as stored when there is none: no HOME for a server's folder).
std::string resolvedPath(const std::string& stored, const Database& db) {
  if (stored.empty() || std::filesystem::path(stored).is_absolute()) return stored;
  auto base = datasetPathBase(db);
  if (!base) return stored;
  return (std::filesystem::path(*base) / stored).lexically_normal().string();
}

// A server's URL as one file name: scheme, user and password dropped, every other character
// but letters, digits, '.', '-' and '_' made '_'; a long one cut and told apart by its hash.
std::string serverFolderName(const std::string& url) {
  std::string rest = url.substr(url.find("://") + 3);
  const std::size_t slash = rest.find('/'), at = rest.rfind('@', slash);
  if (at != std::string::npos) rest = rest.substr(at + 1);
  std::string name;
  for (char c : rest)
    name += std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_' ? c : '_';
  if (name.size() > 80) name = name.substr(0, 60) + "-" + sha256Hex(url).substr(0, 16);
  return name;
}

Result<DatasetRecord> readRecord(const Statement& s, const Database& db) {
  DatasetRecord r;
  r.id = s.int64(0);
  r.name = s.text(1);
  r.species = s.text(2);
  r.volumePath = resolvedPath(s.text(3), db);
  r.volumeChecksum = s.text(4);
  r.labelsPath = resolvedPath(s.optionalText(5).value_or(""), db);
  r.labelsChecksum = s.optionalText(6).value_or("");
  r.namesPath = resolvedPath(s.optionalText(7).value_or(""), db);
  r.geometry.dims = {s.integer(8), s.integer(9), s.integer(10)};
  r.geometry.spacingMm = {s.real(11), s.real(12), s.real(13)};
  r.geometry.originMm = {s.real(14), s.real(15), s.real(16)};
  const auto direction = nlohmann::json::parse(s.text(17), nullptr, false);
  if (!direction.is_array() || direction.size() != 9)
    return fail("dataset '" + r.name + "': stored direction is not 9 numbers");
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 3; ++col) r.geometry.direction.m[row][col] = direction[std::size_t(row * 3 + col)].get<double>();
  r.orientation = s.text(18);
  r.createdAt = s.text(19);
  r.structureCount = s.integer(20);
  if (const auto options = s.optionalText(21)) {
    const auto json = nlohmann::json::parse(*options, nullptr, false);
    if (!json.is_object()) return fail("dataset '" + r.name + "': stored load options are not a JSON object");
    const auto wrong = [&](const char* field, const char* what) {
      return fail("dataset '" + r.name + "': stored load option " + field + " is not " + what);
    };
    if (json.contains("skip_unreadable") && !json["skip_unreadable"].is_boolean()) return wrong("skip_unreadable", "true or false");
    if (json.contains("data_folder") && !json["data_folder"].is_string()) return wrong("data_folder", "a path");
    r.skipUnreadableFiles = json.value("skip_unreadable", false);
    r.dataFolder = json.value("data_folder", "");
    if (json.contains("intensity")) {
      const auto choice = json["intensity"].is_string() ? parseIntensityChoice(json["intensity"].get<std::string>())
                                                        : Result<IntensityChoice>(fail("not a string"));
      if (!choice) return wrong("intensity", "auto, hu or plain");
      r.intensity = *choice;
    }
    for (const auto& [field, value] : {std::pair{"intercept", &r.intercept}, std::pair{"slope", &r.slope}}) {
      if (!json.contains(field)) continue;
      if (!json[field].is_number() || !std::isfinite(json[field].get<double>())) return wrong(field, "a finite number");
      *value = json[field].get<double>();
    }
    if (r.slope && *r.slope == 0) return wrong("slope", "a number other than 0");
    if (json.contains("modality")) {
      if (!json["modality"].is_string() || !isDicomModalityCode(json["modality"].get<std::string>()))
        return wrong("modality", "a DICOM modality code");
      r.modality = json["modality"].get<std::string>();
    }
  }
  return r;
}

std::optional<std::string> nonEmpty(const std::string& s) {
  if (s.empty()) return std::nullopt;
  return s;
}

// The structures of dataset `id` (with their review states; absent: not started), inside the
// caller's transaction.
Status insertStructures(Database& d, std::int64_t id, const std::vector<Structure>& structures,
                        const ReviewStates& review = {}) {
  // review_state only when a structure has one other than the column's default: the column
  // exists from schema 13 on.
  const bool states = std::any_of(structures.begin(), structures.end(), [&](const Structure& st) {
    const auto state = review.find(st.id);
    return state != review.end() && state->second != ReviewState::NotStarted;
  });
  auto add = d.prepare(std::string("INSERT INTO structures (dataset_id, label, structure_id, name, colour_r, colour_g,"
                                   " colour_b, system, description") +
                       (states ? ", review_state) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)"
                               : ") VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9)"));
  if (!add) return tl::unexpected(add.error());
  for (const Structure& st : structures) {
    add->reset();
    const auto state = review.find(st.id);
    if (states) add->bind(10, reviewStateId(state == review.end() ? ReviewState::NotStarted : state->second));
    add->bind(1, id)
        .bind(2, int(st.label))
        .bind(3, st.id)
        .bind(4, st.displayName)
        .bind(5, double(st.colour[0]))
        .bind(6, double(st.colour[1]))
        .bind(7, double(st.colour[2]))
        .bind(8, st.system)
        .bind(9, st.description);
    if (auto s = add->run(); !s)
      return tl::unexpected(withContext("structure " + std::to_string(st.label) + " '" + st.id + "'", s.error()));
  }
  return {};
}

}  // namespace

Result<std::string> datasetPathBase(const Database& db) {
  if (!isPostgresUrl(db.path())) return std::filesystem::absolute(db.path()).parent_path().string();
  auto defaultDatabase = defaultDatabasePath();
  if (!defaultDatabase) return tl::unexpected(defaultDatabase.error());
  return (std::filesystem::path(*defaultDatabase).parent_path() / "servers" / serverFolderName(db.path())).string();
}

Result<std::int64_t> registerDataset(Database& db, const DatasetRecord& record,
                                     const std::vector<Structure>& structures, bool replace) {
  std::int64_t id = 0;
  auto status = db.writeTransaction([&](Database& d) -> Status {
    auto exists = d.prepare("SELECT 1 FROM datasets WHERE name = ?1");
    if (!exists) return tl::unexpected(exists.error());
    exists->bind(1, record.name);
    auto row = exists->step();
    if (!row) return tl::unexpected(row.error());
    if (*row && !replace)
      return fail(ErrorKind::Conflict, "a dataset named '" + record.name +
                                           "' is already imported; choose another --name (or --replace it)");
    if (*row) {
      // The structures go with their dataset (ON DELETE CASCADE).
      auto remove = d.prepare("DELETE FROM datasets WHERE name = ?1");
      if (!remove) return tl::unexpected(remove.error());
      remove->bind(1, record.name);
      if (auto s = remove->run(); !s) return s;
    }

    nlohmann::json loadOptions = nlohmann::json::object();
    if (record.skipUnreadableFiles) loadOptions["skip_unreadable"] = true;
    if (!record.dataFolder.empty()) loadOptions["data_folder"] = record.dataFolder;
    if (record.intensity != IntensityChoice::Auto) loadOptions["intensity"] = intensityChoiceName(record.intensity);
    if (record.intercept) loadOptions["intercept"] = *record.intercept;
    if (record.slope) loadOptions["slope"] = *record.slope;
    if (!record.modality.empty()) loadOptions["modality"] = record.modality;
    // load_options only when there are some: the column exists from schema 9 on.
    auto insert = d.prepare(
        std::string("INSERT INTO datasets (name, species, volume_path, volume_checksum, labels_path, labels_checksum,"
                    " names_path, dim_x, dim_y, dim_z, spacing_x, spacing_y, spacing_z, origin_x, origin_y, origin_z,"
                    " direction, orientation") +
        (loadOptions.empty() ? ") VALUES (" : ", load_options) VALUES (") +
        "?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, ?18" +
        (loadOptions.empty() ? ")" : ", ?19)") + " RETURNING id");
    if (!insert) return tl::unexpected(insert.error());
    nlohmann::json direction = nlohmann::json::array();
    for (int row = 0; row < 3; ++row)
      for (int col = 0; col < 3; ++col) direction.push_back(record.geometry.direction.m[row][col]);
    const Geometry& g = record.geometry;
    insert->bind(1, record.name)
        .bind(2, record.species)
        .bind(3, record.volumePath)
        .bind(4, record.volumeChecksum)
        .bind(5, nonEmpty(record.labelsPath))
        .bind(6, nonEmpty(record.labelsChecksum))
        .bind(7, nonEmpty(record.namesPath))
        .bind(8, g.dims.x)
        .bind(9, g.dims.y)
        .bind(10, g.dims.z)
        .bind(11, g.spacingMm[0])
        .bind(12, g.spacingMm[1])
        .bind(13, g.spacingMm[2])
        .bind(14, g.originMm[0])
        .bind(15, g.originMm[1])
        .bind(16, g.originMm[2])
        .bind(17, direction.dump())
        .bind(18, record.orientation);
    if (!loadOptions.empty()) insert->bind(19, loadOptions.dump());
    auto inserted = insert->insertReturningId();
    if (!inserted) return tl::unexpected(inserted.error());
    id = *inserted;

    return insertStructures(d, id, structures);
  });
  if (!status) return tl::unexpected(status.error());
  return id;
}

Status saveDatasetLabels(Database& db, const std::string& name, const std::string& labelsPath,
                         const std::string& labelsChecksum, const std::string& namesPath,
                         const std::vector<Structure>& structures, const ReviewStates* review) {
  return db.writeTransaction([&](Database& d) -> Status {
    auto find = d.prepare("SELECT id FROM datasets WHERE name = ?1");
    if (!find) return tl::unexpected(find.error());
    find->bind(1, name);
    auto row = find->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return fail(ErrorKind::NotFound, "no imported dataset is named '" + name + "'");
    const std::int64_t id = find->int64(0);
    auto update = d.prepare("UPDATE datasets SET labels_path = ?1, labels_checksum = ?2, names_path = ?3 WHERE id = ?4");
    if (!update) return tl::unexpected(update.error());
    update->bind(1, nonEmpty(labelsPath)).bind(2, nonEmpty(labelsChecksum)).bind(3, nonEmpty(namesPath)).bind(4, id);
    if (auto s = update->run(); !s) return s;
    ReviewStates kept;
    if (!review) {
      auto stored = datasetReviewStates(d, id);
      if (!stored) return tl::unexpected(stored.error());
      kept = std::move(*stored);
    }
    auto clear = d.prepare("DELETE FROM structures WHERE dataset_id = ?1");
    if (!clear) return tl::unexpected(clear.error());
    clear->bind(1, id);
    if (auto s = clear->run(); !s) return s;
    return insertStructures(d, id, structures, review ? *review : kept);
  });
}

Status setStructureSystem(Database& db, const std::string& name, const std::string& structureId,
                          const std::string& system) {
  return db.writeTransaction([&](Database& d) -> Status {
    auto find = d.prepare(
        "SELECT d.id, s.structure_id FROM datasets d LEFT JOIN structures s ON s.dataset_id = d.id AND"
        " s.structure_id = ?2 WHERE d.name = ?1");
    if (!find) return tl::unexpected(find.error());
    find->bind(1, name).bind(2, structureId);
    auto row = find->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return fail(ErrorKind::NotFound, "no imported dataset is named '" + name + "'");
    const std::int64_t id = find->int64(0);
    if (find->text(1).empty())
      return fail(ErrorKind::NotFound, "imported dataset '" + name + "' has no structure '" + structureId + "'");
    auto update = d.prepare("UPDATE structures SET system = ?1 WHERE dataset_id = ?2 AND structure_id = ?3");
    if (!update) return tl::unexpected(update.error());
    update->bind(1, system).bind(2, id).bind(3, structureId);
    return update->run();
  });
}

const char* reviewStateId(ReviewState state) {
  switch (state) {
    case ReviewState::InProgress: return "in_progress";
    case ReviewState::Completed: return "completed";
    case ReviewState::Flagged: return "flagged";
    case ReviewState::NotStarted: break;
  }
  return "not_started";
}

const char* reviewStateText(ReviewState state) {
  switch (state) {
    case ReviewState::InProgress: return "in progress";
    case ReviewState::Completed: return "completed";
    case ReviewState::Flagged: return "flagged";
    case ReviewState::NotStarted: break;
  }
  return "not started";
}

std::optional<ReviewState> reviewStateNamed(const std::string& name) {
  for (ReviewState s : kReviewStates)
    if (name == reviewStateId(s) || name == reviewStateText(s)) return s;
  return std::nullopt;
}

Result<ReviewStates> datasetReviewStates(Database& db, std::int64_t datasetId) {
  auto s = db.prepare("SELECT structure_id, review_state FROM structures WHERE dataset_id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, datasetId);
  ReviewStates out;
  while (true) {
    auto row = s->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    const std::string state = s->text(1);
    const auto parsed = reviewStateNamed(state);
    if (!parsed)
      return fail(ErrorKind::Invalid, "structure '" + s->text(0) + "': unknown review state '" + state + "'");
    out[s->text(0)] = *parsed;
  }
  return out;
}

Result<std::vector<DatasetRecord>> listDatasets(Database& db) {
  auto s = db.prepare(std::string(kSelectDataset) + " ORDER BY d.name");
  if (!s) return tl::unexpected(s.error());
  std::vector<DatasetRecord> out;
  while (true) {
    auto row = s->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    auto r = readRecord(*s, db);
    if (!r) return tl::unexpected(r.error());
    out.push_back(std::move(*r));
  }
  return out;
}

Result<std::optional<DatasetRecord>> findDataset(Database& db, const std::string& name) {
  auto s = db.prepare(std::string(kSelectDataset) + " WHERE d.name = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, name);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<DatasetRecord>{};
  auto r = readRecord(*s, db);
  if (!r) return tl::unexpected(r.error());
  return std::optional<DatasetRecord>(std::move(*r));
}

Result<std::vector<Structure>> datasetStructures(Database& db, std::int64_t datasetId) {
  auto s = db.prepare(
      "SELECT label, structure_id, name, colour_r, colour_g, colour_b, system, description FROM structures"
      " WHERE dataset_id = ?1 ORDER BY label");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, datasetId);
  std::vector<Structure> out;
  while (true) {
    auto row = s->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    Structure st;
    st.label = static_cast<std::uint16_t>(s->integer(0));
    st.id = s->text(1);
    st.displayName = s->text(2);
    st.colour = {float(s->real(3)), float(s->real(4)), float(s->real(5))};
    st.system = s->text(6);
    st.description = s->text(7);
    out.push_back(std::move(st));
  }
  return out;
}

DatasetFiles datasetFiles(const DatasetRecord& record) {
  DatasetFiles files;
  files.volumePath = record.volumePath;
  files.labelsPath = record.labelsPath;
  files.namesPath = record.namesPath;
  files.id = record.name;
  files.skipUnreadableFiles = record.skipUnreadableFiles;
  files.dataFolder = record.dataFolder;
  files.intensity = record.intensity;
  files.intercept = record.intercept;
  files.slope = record.slope;
  files.modality = record.modality;
  return files;
}

std::string loadOptionArguments(const DatasetRecord& record) {
  std::string out;
  if (record.intensity != IntensityChoice::Auto) out += std::string(" --intensity ") + intensityChoiceName(record.intensity);
  char number[64];
  if (record.intercept) std::snprintf(number, sizeof number, " --intercept %.17g", *record.intercept), out += number;
  if (record.slope) std::snprintf(number, sizeof number, " --slope %.17g", *record.slope), out += number;
  // (a code may hold spaces: quoted then for a shell)
  if (!record.modality.empty())
    out += record.modality.find(' ') == std::string::npos ? " --modality " + record.modality
                                                          : " --modality '" + record.modality + "'";
  return out;
}

Result<DatasetFiles> verifiedDatasetFiles(const DatasetRecord& record) {
  const std::string reimport = "anatomy-tutor import --volume " + record.volumePath +
                               (record.labelsPath.empty() ? "" : " --labels " + record.labelsPath) +
                               (record.namesPath.empty() ? "" : " --names " + record.namesPath) +
                               (record.skipUnreadableFiles ? " --skip-unreadable" : "") +
                               (record.dataFolder.empty() ? "" : " --nrrd-data " + record.dataFolder) +
                               loadOptionArguments(record) + " --name " +
                               record.name + " --replace";
  for (const auto& [path, recorded, what] : {std::tuple{&record.volumePath, &record.volumeChecksum, "volume"},
                                             std::tuple{&record.labelsPath, &record.labelsChecksum, "labels"}}) {
    if (path->empty()) continue;
    // (a detached NRRD imported before checksums covered its data files: its header is checked)
    auto now = checksumAsRecorded(*path, *recorded, record.dataFolder);
    if (!now)
      return tl::unexpected(withContext("dataset '" + record.name + "': its " + what + " cannot be read", now.error()));
    if (*now != *recorded)
      return fail(ErrorKind::Conflict,
                  "dataset '" + record.name + "': its " + what + " " + *path +
                      " has changed since it was imported (checksum now " + now->substr(0, 19) + "…, recorded " +
                      recorded->substr(0, 19) + "…); if the new content is meant, register it again: " + reimport);
  }
  return datasetFiles(record);
}

}  // namespace at::db
