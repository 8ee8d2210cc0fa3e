// Several store calls as one transaction (db/all_or_nothing.h): the stores' own transactions join
// it, so a failure anywhere in the body leaves nothing of it stored.
#include <doctest/doctest.h>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/all_or_nothing.h"
#include "db/preset_store.h"
#include "test_databases.h"
#include "test_support.h"

using namespace at;

TEST_CASE("AllOrNothing_AFailureAfterSeveralStoreWrites_LeavesNoneOfThem") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  for (int failAfter = 0; failAfter <= 3; ++failAfter) {
    CAPTURE(failAfter);
    auto st = db::writeAllOrNothing(*db, [&]() -> Status {
      for (int i = 0; i < 3; ++i) {
        if (i == failAfter) return fail("stop");
        if (auto ok = db::savePreset(*db, {"p" + std::to_string(i), std::nullopt, "wdt", "{}"}); !ok) return ok;
      }
      return failAfter == 3 ? fail("stop at the end") : Status{};
    });
    CHECK_FALSE(st);
    auto all = db::listPresets(*db);
    REQUIRE(all);
    CHECK(all->empty());
  }
  auto st = db::writeAllOrNothing(*db, [&]() -> Status {
    for (int i = 0; i < 3; ++i)
      if (auto ok = db::savePreset(*db, {"p" + std::to_string(i), std::nullopt, "wdt", "{}"}); !ok) return ok;
    return {};
  });
  REQUIRE(st);
  auto all = db::listPresets(*db);
  REQUIRE(all);
  CHECK(all->size() == 3);
  // Outside it, each store's transaction is its own again.
  REQUIRE(db::savePreset(*db, {"q", std::nullopt, "wdt", "{}"}));
  CHECK(db::listPresets(*db)->size() == 4);
}
