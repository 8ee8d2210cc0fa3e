#include "scan_catalogue.h"

#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#include "data_paths.h"

namespace at::app {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

Status onlyKeys(const json& j, const std::string& where, const std::set<std::string>& allowed) {
  for (const auto& [key, value] : j.items())
    if (!allowed.count(key)) return fail(where + ": unknown field '" + key + "'");
  return {};
}

Result<std::string> text(const json& j, const std::string& key, const std::string& where, bool required) {
  if (!j.contains(key)) {
    if (required) return fail(where + "." + key + ": missing");
    return std::string();
  }
  if (!j[key].is_string()) return fail(where + "." + key + ": must be a string");
  return j[key].get<std::string>();
}

}  // namespace

Result<StructureCatalogue> loadStructureCatalogue(const fs::path& path) {
  const std::string file = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail(ErrorKind::NotFound, file + ": cannot open the structure catalogue");
  json j;
  try {
    j = json::parse(in);
  } catch (const json::exception& e) {
    return fail(file + ": not valid JSON (" + std::string(e.what()) + ")");
  }
  if (!j.is_object()) return fail(file + ": expected an object with \"schema\", \"dataset\" and \"structures\"");
  if (auto ok = onlyKeys(j, file, {"schema", "dataset", "about", "structures"}); !ok) return tl::unexpected(ok.error());
  if (!j.contains("schema") || j["schema"] != 1) return fail(file + ": schema: must be 1");
  StructureCatalogue catalogue;
  auto dataset = text(j, "dataset", file, true);
  if (!dataset) return tl::unexpected(dataset.error());
  catalogue.dataset = *dataset;
  auto about = text(j, "about", file, false);
  if (!about) return tl::unexpected(about.error());
  catalogue.about = *about;
  if (!j.contains("structures") || !j["structures"].is_array()) return fail(file + ": structures: must be a list");
  std::set<std::string> ids;
  for (std::size_t n = 0; n < j["structures"].size(); ++n) {
    const json& s = j["structures"][n];
    const std::string where = file + ": structures[" + std::to_string(n) + "]";
    if (!s.is_object()) return fail(where + ": must be an object");
    if (auto ok = onlyKeys(s, where, {"id", "system", "side", "description", "review_state", "review"}); !ok) return tl::unexpected(ok.error());
    CatalogueEntry e;
    for (auto [key, field] : {std::pair{"id", &e.id}, {"system", &e.system}, {"side", &e.side},
                              {"description", &e.description}, {"review_state", &e.reviewState}, {"review", &e.review}}) {
      auto value = text(s, key, where, true);
      if (!value) return tl::unexpected(value.error());
      if (value->empty()) return fail(where + "." + key + ": must not be empty");
      *field = *value;
    }
    if (e.side != "left" && e.side != "right" && e.side != "midline")
      return fail(where + ".side: must be left, right or midline, not '" + e.side + "'");
    if (e.reviewState != "completed" && e.reviewState != "flagged")
      return fail(where + ".review_state: must be completed or flagged, not '" + e.reviewState + "'");
    if (!ids.insert(e.id).second) return fail(where + ".id: '" + e.id + "' is listed twice");
    catalogue.structures.push_back(std::move(e));
  }
  return catalogue;
}

fs::path catalogueFileFor(const std::string& datasetId) {
  return dataSubdirectory("segmentations") / datasetId / "structures.json";
}

void applyCatalogue(Dataset& dataset, const StructureCatalogue& catalogue) {
  for (Structure& s : dataset.structures)
    for (const CatalogueEntry& e : catalogue.structures)
      if (e.id == s.id) {
        s.system = e.system;
        s.description = e.description;
      }
  if (!catalogue.about.empty()) dataset.provenance.notes.push_back(catalogue.about);
}

}  // namespace at::app
