// Checks on commands run as a user would (test::runApp).
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.h"

namespace at::test {

// A path in single quotes, for the shell that runApp starts.
inline std::string quotedPath(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

// A command that must succeed and print one JSON object.
inline nlohmann::json runAppJson(const std::string& args) {
  const auto r = runApp(args);
  REQUIRE_MESSAGE(r.exitCode == 0, args << ": " << r.err);
  return nlohmann::json::parse(r.out);
}

// A failing command says what is wrong on exactly one line of stderr.
inline void checkOneLineError(const CommandResult& r, const std::string& mustMention) {
  CHECK(r.exitCode != 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find(mustMention) != std::string::npos);
  CHECK(r.err.rfind("anatomy-tutor: ", 0) == 0);
}

// The names of the imported datasets in `db`, through `anatomy-tutor datasets --json`.
inline std::vector<std::string> importedDatasetNames(const std::filesystem::path& db) {
  auto listed = runApp("datasets --json --db '" + db.string() + "'");
  REQUIRE_MESSAGE(listed.exitCode == 0, listed.err);
  const nlohmann::json all = nlohmann::json::parse(listed.out);
  std::vector<std::string> names;
  for (const nlohmann::json& d : all.at("datasets"))
    if (!d.value("builtin", true)) names.push_back(d.at("id").get<std::string>());
  return names;
}

}  // namespace at::test
