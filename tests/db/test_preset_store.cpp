#include <doctest/doctest.h>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/preset_store.h"
#include "test_databases.h"
#include "test_support.h"

using namespace at;

TEST_CASE("PresetStore_SaveThenFind_ReturnsTheSameRecordAndReplacesById") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  const db::StoredPreset a{"my_cochlea", std::string("cochlea"), "wdt", R"({"name": "My cochlea"})"};
  REQUIRE(db::savePreset(*db, a).has_value());
  auto found = db::findPreset(*db, "my_cochlea");
  REQUIRE(found.has_value());
  REQUIRE(found->has_value());
  CHECK(**found == a);

  db::StoredPreset b = a;
  b.mode = "outline";
  b.json = R"({"name": "My cochlea, outlined"})";
  REQUIRE(db::savePreset(*db, b).has_value());
  auto again = db::findPreset(*db, "my_cochlea");
  REQUIRE(again.has_value());
  REQUIRE(again->has_value());
  CHECK(**again == b);
  auto all = db::listPresets(*db);
  REQUIRE(all.has_value());
  CHECK(all->size() == 1);
}

TEST_CASE("PresetStore_ListPresets_IsSortedByIdAndFiltersByStructure") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  REQUIRE(db::savePreset(*db, {"z_any", std::nullopt, "bare", "{}"}).has_value());
  REQUIRE(db::savePreset(*db, {"b_cochlea", std::string("cochlea"), "wdt", "{}"}).has_value());
  REQUIRE(db::savePreset(*db, {"a_stapes", std::string("stapes"), "wdt", "{}"}).has_value());
  auto all = db::listPresets(*db);
  REQUIRE(all.has_value());
  REQUIRE(all->size() == 3);
  CHECK((*all)[0].id == "a_stapes");
  CHECK((*all)[1].id == "b_cochlea");
  CHECK((*all)[2].id == "z_any");
  CHECK_FALSE((*all)[2].structure.has_value());
  auto cochlea = db::listPresets(*db, std::string("cochlea"));
  REQUIRE(cochlea.has_value());
  REQUIRE(cochlea->size() == 1);
  CHECK(cochlea->front().id == "b_cochlea");
}

TEST_CASE("PresetStore_FindPreset_OfAnUnknownId_IsEmptyNotAnError") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  auto none = db::findPreset(*db, "missing");
  REQUIRE(none.has_value());
  CHECK_FALSE(none->has_value());
}

TEST_CASE("PresetStore_SavePreset_WithEmptyFields_IsRefusedNamingTheField") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  auto noId = db::savePreset(*db, {"", std::nullopt, "wdt", "{}"});
  REQUIRE_FALSE(noId.has_value());
  CHECK(noId.error().message.find("'id'") != std::string::npos);
  auto noJson = db::savePreset(*db, {"x", std::nullopt, "wdt", ""});
  REQUIRE_FALSE(noJson.has_value());
  CHECK(noJson.error().message.find("'json'") != std::string::npos);
  auto all = db::listPresets(*db);
  REQUIRE(all.has_value());
  CHECK(all->empty());
}
