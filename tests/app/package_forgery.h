// Packages as an attacker makes them: a legitimate `course export`, altered, with the manifest's
// sizes and checksums recomputed so that every integrity check passes.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

#include "../package/tar_files.h"
#include "core/sha256.h"

namespace at::test {

// The manifest's files list made to match `entries` again (size and SHA-256 of each listed entry;
// entries it does not list are added, with the manifest kept first).
inline void rechecksum(std::vector<TarEntry>& entries) {
  TarEntry* manifestEntry = findEntry(entries, "manifest.json");
  auto manifest = nlohmann::json::parse(manifestEntry->data);
  nlohmann::json files = nlohmann::json::array();
  for (const TarEntry& e : entries) {
    if (e.name == "manifest.json") continue;
    Sha256 sha;
    sha.update(e.data);
    files.push_back({{"path", e.name}, {"size", e.data.size()}, {"sha256", sha.hex()}});
  }
  manifest["files"] = files;
  manifestEntry->data = manifest.dump(2);
}

// `package` read, changed by `change(entries, manifest JSON, course JSON)`, re-checksummed and
// written to `out`.
template <class Change>
std::filesystem::path forgePackage(const std::filesystem::path& package, const std::filesystem::path& out, Change change) {
  auto entries = readTar(package);
  auto manifest = nlohmann::json::parse(findEntry(entries, "manifest.json")->data);
  auto course = nlohmann::json::parse(findEntry(entries, "course.json")->data);
  change(entries, manifest, course);
  findEntry(entries, "manifest.json")->data = manifest.dump(2);
  findEntry(entries, "course.json")->data = course.dump(2);
  rechecksum(entries);
  writeTar(out, entries);
  return out;
}

}  // namespace at::test
