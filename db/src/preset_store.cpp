#include "db/preset_store.h"

#include "database.h"

namespace at::db {

namespace {
StoredPreset readRow(const Statement& st) {
  return StoredPreset{st.text(0), st.optionalText(1), st.text(2), st.text(3)};
}
}  // namespace

Status savePreset(Database& db, const StoredPreset& preset) {
  if (preset.id.empty()) return fail("preset store: field 'id' must not be empty");
  if (preset.mode.empty()) return fail("preset store: preset '" + preset.id + "': field 'mode' must not be empty");
  if (preset.json.empty()) return fail("preset store: preset '" + preset.id + "': field 'json' must not be empty");
  return db.writeTransaction([&](Database& d) -> Status {
    auto st = d.prepare(
        "INSERT INTO presets (id, structure, mode, json) VALUES (?1, ?2, ?3, ?4) "
        "ON CONFLICT(id) DO UPDATE SET structure = excluded.structure, mode = excluded.mode, json = excluded.json");
    if (!st) return tl::unexpected(st.error());
    st->bind(1, preset.id).bind(2, preset.structure).bind(3, preset.mode).bind(4, preset.json);
    return st->run();
  });
}

Result<std::vector<StoredPreset>> listPresets(Database& db, const std::optional<std::string>& structure) {
  auto st = structure ? db.prepare("SELECT id, structure, mode, json FROM presets WHERE structure = ?1 ORDER BY id")
                      : db.prepare("SELECT id, structure, mode, json FROM presets ORDER BY id");
  if (!st) return tl::unexpected(st.error());
  if (structure) st->bind(1, *structure);
  std::vector<StoredPreset> out;
  for (;;) {
    auto row = st->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    out.push_back(readRow(*st));
  }
  return out;
}

Result<std::optional<StoredPreset>> findPreset(Database& db, const std::string& id) {
  auto st = db.prepare("SELECT id, structure, mode, json FROM presets WHERE id = ?1");
  if (!st) return tl::unexpected(st.error());
  st->bind(1, id);
  auto row = st->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<StoredPreset>{};
  return std::optional<StoredPreset>{readRow(*st)};
}

}  // namespace at::db
