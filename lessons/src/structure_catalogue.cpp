#include "lessons/structure_catalogue.h"

#include <set>

#include <nlohmann/json.hpp>

#include "quiz/sided_names.h"
#include "shipped_catalogue_texts.h"

namespace at::lessons {
namespace {

using nlohmann::json;

Result<std::vector<std::string>> stringList(const json& entry, const char* key, const std::string& path) {
  std::vector<std::string> out;
  if (!entry.contains(key)) return out;
  const json& list = entry[key];
  if (!list.is_array()) return fail(path + "." + key + ": must be an array of strings");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string at = path + "." + key + "[" + std::to_string(i) + "]";
    if (!list[i].is_string() || list[i].get<std::string>().empty()) return fail(at + ": must be a non-empty string");
    const std::string name = list[i].get<std::string>();
    if (quiz::splitSide(name).side != quiz::Side::None) {
      return fail(at + ": '" + name + "' carries a side; names are written without it (the entry's \"side\" says it)");
    }
    out.push_back(name);
  }
  return out;
}

Result<CatalogueEntry> readEntry(const json& j, const std::string& path) {
  if (!j.is_object()) return fail(path + ": must be an object");
  for (const auto& [key, value] : j.items()) {
    if (key != "id" && key != "name" && key != "side" && key != "synonyms" && key != "latin" && key != "system") {
      return fail(path + "." + key + ": unknown field");
    }
  }
  CatalogueEntry e;
  for (const char* key : {"id", "name"}) {
    if (!j.contains(key) || !j[key].is_string() || j[key].get<std::string>().empty()) {
      return fail(path + "." + key + ": must be a non-empty string");
    }
  }
  e.structureId = j["id"].get<std::string>();
  e.name = j["name"].get<std::string>();
  if (quiz::splitSide(e.name).side != quiz::Side::None) {
    return fail(path + ".name: '" + e.name + "' carries a side; write it without (\"side\" says it)");
  }
  if (j.contains("side")) {
    const std::string side = j["side"].is_string() ? j["side"].get<std::string>() : "";
    if (side == "left") e.side = quiz::Side::Left;
    else if (side == "right") e.side = quiz::Side::Right;
    else return fail(path + ".side: must be \"left\" or \"right\" (leave it out for unpaired structures)");
  }
  auto synonyms = stringList(j, "synonyms", path);
  if (!synonyms) return tl::unexpected(synonyms.error());
  e.synonyms = *synonyms;
  auto latin = stringList(j, "latin", path);
  if (!latin) return tl::unexpected(latin.error());
  e.latin = *latin;
  if (j.contains("system")) {
    if (!j["system"].is_string()) return fail(path + ".system: must be a string");
    e.system = j["system"].get<std::string>();
  }
  return e;
}

}  // namespace

const CatalogueEntry* StructureCatalogue::find(const std::string& structureId) const {
  for (const CatalogueEntry& e : entries)
    if (e.structureId == structureId) return &e;
  return nullptr;
}

Result<StructureCatalogue> parseStructureCatalogue(const std::string& text, const std::string& sourceName) {
  const json doc = json::parse(text, nullptr, false);
  if (doc.is_discarded()) return fail(sourceName + ": not valid JSON");
  if (!doc.is_object()) return fail(sourceName + ": must be an object");
  for (const auto& [key, value] : doc.items()) {
    if (key != "schema" && key != "dataset" && key != "title" && key != "structures") {
      return fail(sourceName + ": " + key + ": unknown field");
    }
  }
  if (!doc.contains("schema") || !doc["schema"].is_number_integer() || doc["schema"].get<int>() != 1) {
    return fail(sourceName + ": schema: must be 1");
  }
  if (!doc.contains("dataset") || !doc["dataset"].is_string() || doc["dataset"].get<std::string>().empty()) {
    return fail(sourceName + ": dataset: must be a non-empty string");
  }
  if (!doc.contains("structures") || !doc["structures"].is_array()) {
    return fail(sourceName + ": structures: must be an array");
  }
  StructureCatalogue catalogue;
  catalogue.datasetId = doc["dataset"].get<std::string>();
  if (doc.contains("title")) {
    if (!doc["title"].is_string()) return fail(sourceName + ": title: must be a string");
    catalogue.title = doc["title"].get<std::string>();
  }
  std::set<std::string> ids;
  for (std::size_t i = 0; i < doc["structures"].size(); ++i) {
    const std::string path = sourceName + ": structures[" + std::to_string(i) + "]";
    auto entry = readEntry(doc["structures"][i], path);
    if (!entry) return tl::unexpected(entry.error());
    if (!ids.insert(entry->structureId).second) {
      return fail(path + ".id: '" + entry->structureId + "' is listed twice");
    }
    catalogue.entries.push_back(std::move(*entry));
  }
  return catalogue;
}

const std::vector<StructureCatalogue>& shippedCatalogues() {
  static const std::vector<StructureCatalogue> catalogues = [] {
    std::vector<StructureCatalogue> out;
    for (const auto& [file, text] : detail::shippedCatalogueTexts()) {
      auto parsed = parseStructureCatalogue(std::string(text), std::string(file));
      if (parsed) out.push_back(std::move(*parsed));  // a broken file fails the catalogue tests
    }
    return out;
  }();
  return catalogues;
}

const StructureCatalogue* shippedCatalogue(const std::string& datasetId) {
  for (const StructureCatalogue& c : shippedCatalogues())
    if (c.datasetId == datasetId) return &c;
  return nullptr;
}

}  // namespace at::lessons
