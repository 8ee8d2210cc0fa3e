// Presets an expert saved from the desktop app, in the `presets` table (id, structure, mode, json).
// The store keeps the preset's JSON text as given; the caller validates it (render::parsePreset)
// before saving and after loading: db/ does not depend on render/.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "db/connection.h"

namespace at::db {

struct StoredPreset {
  std::string id;                        // unique; saving an existing id replaces it
  std::optional<std::string> structure;  // structure id it was made for, or none for any
  std::string mode;                      // render mode name ("wdt", "bare", …)
  std::string json;                      // the preset file's text
  bool operator==(const StoredPreset&) const = default;
};

// Inserts or replaces by id. Errors: empty id, mode or json (message names the field).
Status savePreset(Database& db, const StoredPreset& preset);
// Every stored preset, sorted by id; only those made for `structure` when it is given.
Result<std::vector<StoredPreset>> listPresets(Database& db, const std::optional<std::string>& structure = {});
// The preset with `id`, or nullopt when there is none.
Result<std::optional<StoredPreset>> findPreset(Database& db, const std::string& id);

}  // namespace at::db
