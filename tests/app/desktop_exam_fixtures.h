// The desktop exam tests' fixtures: a student who finished the temporal-bone exam's prerequisite
// lessons, and the items of the attempt as stored.
#pragma once

#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)

namespace at::test {

// A database whose user 'examinee' finished the exam's prerequisite lessons.
inline void prepareStudent(const std::filesystem::path& db) {
  auto database = at::db::Database::open(db.string());
  REQUIRE(database);
  REQUIRE(database->exec("INSERT OR IGNORE INTO users (name) VALUES ('examinee')"));  // an earlier run may have made it
  for (const char* lesson : {"inner_ear", "facial_nerve", "middle_ear"}) {
    auto done = database->prepare("INSERT INTO attempts (user_id, lesson_id, mode, started_at, finished_at, score)"
                                  " SELECT id, ?1, 'guided', 100, 200, 1 FROM users WHERE name = 'examinee'");
    REQUIRE(done);
    done->bind(1, std::string(lesson));
    REQUIRE(done->run());
  }
}

struct StoredItem {
  int position = 0;
  std::string kind, structure, locateView;
  std::vector<std::string> choices;
  bool answered = false;
  bool correct = false;
};

inline std::vector<StoredItem> storedItems(const std::filesystem::path& db) {
  auto database = at::db::Database::open(db.string());
  REQUIRE(database);
  auto q = database->prepare("SELECT position, kind, structure, locate_view, choices, answer IS NOT NULL, coalesce(correct, 0)"
                             " FROM exam_items ORDER BY position");
  REQUIRE(q);
  std::vector<StoredItem> items;
  while (true) {
    auto row = q->step();
    REQUIRE(row);
    if (!*row) break;
    StoredItem item;
    item.position = q->integer(0);
    item.kind = q->text(1);
    item.structure = q->text(2);
    item.locateView = q->text(3);
    item.choices = nlohmann::json::parse(q->text(4)).get<std::vector<std::string>>();
    item.answered = q->integer(5) != 0;
    item.correct = q->integer(6) != 0;
    items.push_back(item);
  }
  return items;
}

}  // namespace at::test
