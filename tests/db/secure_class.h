// A class on a fresh class server for the security tests: the toy course, a coordinator, an
// instructor and two students, each with their own login (a URL that connects as them).
#pragma once

#include <doctest/doctest.h>

#include <unistd.h>

#include <atomic>
#include <string>
#include <vector>

#include "db/class_accounts.h"
#include "db/class_lesson_keys.h"
#include "db/class_server.h"
#include "db/course_store.h"
#include "lessons/lesson_engine.h"
#include "test_databases.h"
#include "toy_course.h"

namespace at::test {

using namespace at::db;

// Login names are cluster-wide; each test makes its own.
inline std::string uniqueLogin(const std::string& stem) {
  static std::atomic<int> counter{0};
  return stem + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

// `url` (the administrator's) with `login` and `password` in place of its user and password.
inline std::string loginUrl(const std::string& url, const std::string& login, const std::string& password) {
  const auto scheme = url.find("://") + 3;
  const auto at = url.find('@', scheme);
  REQUIRE(at != std::string::npos);
  return url.substr(0, scheme) + login + ":" + password + url.substr(at);
}

// The toy course's answer keys, resolved on the toy dataset as an instructor's machine would.
inline std::vector<std::string> toyLessonKeys() {
  ToyKeys keys;
  const lessons::Course course = toyCourse();
  auto all = courseLessonKeys(course, keys, lessons::gradingContext(toyStructures(), course));
  REQUIRE_MESSAGE(all, (all ? "" : all.error().message));
  return *all;
}

// A class on a fresh server with the toy course: its coordinator, an instructor and two students,
// each with their own login, and each connected as themselves. The instructor has published the
// course's answer keys (unless `publishKeys` is false), so the server grades lesson answers.
struct SecureClass {
  std::string adminUrl;
  Database admin;
  std::string code;
  std::string coordinator = uniqueLogin("ada"), instructor = uniqueLogin("lee"), sam = uniqueLogin("sam"),
              eve = uniqueLogin("eve");
  std::string samUrl, eveUrl, coordinatorUrl, instructorUrl;

  explicit SecureClass(const std::string& url, bool publishKeys = true) : adminUrl(url), admin(openAt(url)) {
    REQUIRE(storeCourse(admin, test::toyCourse(), "toy"));
    auto made = createClass(admin, "Ear anatomy", coordinator);
    REQUIRE_MESSAGE(made, (made ? "" : made.error().message));
    code = made->code;
    coordinatorUrl = account(admin, coordinator, ClassRole::Coordinator);
    Database coordinatorDb = openAt(coordinatorUrl);
    instructorUrl = account(coordinatorDb, instructor, ClassRole::Instructor);
    samUrl = account(coordinatorDb, sam, ClassRole::Student);
    eveUrl = account(coordinatorDb, eve, ClassRole::Student);
    if (publishKeys) {
      Database instructorDb = openAt(instructorUrl);
      auto published = publishLessonKeys(instructorDb, code, toyLessonKeys(), std::nullopt);
      REQUIRE_MESSAGE(published, (published ? "" : published.error().message));
      REQUIRE(*published == 6);
    }
  }

  std::string account(Database& by, const std::string& name, ClassRole role) {
    auto made = createClassAccount(by, code, name, role, std::nullopt);
    REQUIRE_MESSAGE(made, (made ? "" : made.error().message));
    REQUIRE(made->password);
    CHECK(made->password->size() >= 16);
    return loginUrl(adminUrl, name, *made->password);
  }
};

// Every row of every table of the server's schema, read by the administrator: one text (a refused
// operation must leave it byte-identical).
inline std::string everyServerRow(db::Database& admin) {
  auto tables = admin.prepare("SELECT tablename FROM pg_tables WHERE schemaname = current_schema() ORDER BY tablename");
  REQUIRE(tables);
  std::vector<std::string> names;
  while (*tables->step()) names.push_back(tables->text(0));
  REQUIRE(names.size() > 20);
  std::string out;
  for (const std::string& table : names) {
    auto rows = admin.prepare("SELECT coalesce(string_agg(t::text, E'\\n' ORDER BY t::text), '') FROM " + table + " t");
    REQUIRE(rows);
    REQUIRE(*rows->step());
    out += table + ":\n" + rows->text(0) + "\n";
  }
  return out;
}

}  // namespace at::test
