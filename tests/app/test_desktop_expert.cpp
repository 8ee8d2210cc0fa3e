// The desktop app's expert panel: scripted spline edits change the rendered view, and
// "Save as" stores a valid preset in the database and exports it as JSON.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/preset_store.h"
#include "render/preset.h"
#include "desktop_script.h"
#include "test_support.h"
#include "volume/png_image.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

constexpr int kWidth = 1100, kHeight = 480;
constexpr int kExplore = 320, kExpert = 340;  // panel widths at UI scale 1: the view shows between them

// Mean absolute difference per channel over the visible part of the volume view.
double viewDifference(const at::RgbImage& a, const at::RgbImage& b) {
  double sum = 0;
  long n = 0;
  for (int y = 0; y < std::min(a.height, b.height); ++y)
    for (int x = kExplore; x < kWidth - kExpert; ++x) {
      for (int c = 0; c < 3; ++c) sum += std::abs(int(a.pixel(x, y)[c]) - int(b.pixel(x, y)[c]));
      ++n;
    }
  return sum / double(std::max(1L, 3 * n));
}

}  // namespace

TEST_CASE("editing the data TF in the expert panel changes the view, and Save as stores and exports a valid preset") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-expert");
  const fs::path before = dir / "before.png", after = dir / "after.png", exported = dir / "my_cochlea.json",
                 dbPath = dir / "presets.db";
  const json script = {
      {"actions",
       {{{"do", "expert"}},
        {{"do", "wait_field"}},
        {{"do", "screenshot"}, {"path", before.string()}},
        {{"do", "tf_add_point"}, {"tf", "data"}, {"x", 777}, {"rgba", {1, 0, 0, 0.9}}},
        {{"do", "preset_set"}, {"t", 1.0}},
        {{"do", "preset_save"}, {"name", "my_cochlea"}, {"export", exported.string()}},
        {{"do", "wait_field"}}}}};
  at::test::DesktopOptions options;
  options.size = std::to_string(kWidth) + "x" + std::to_string(kHeight);
  options.db = dbPath;
  options.screenshot = after.string();
  const at::test::DesktopRun run = at::test::runDesktopScript(dir, script, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);

  // The preset the panel started from, as the app reported it.
  std::optional<at::render::Preset> original;
  for (const json& e : run.events) {
    if (e.is_object() && e.value("event", "") == "expert") {
      auto p = at::render::parsePreset(e.at("preset").dump(), "expert event");
      REQUIRE_MESSAGE(p.has_value(), p.error().message);
      original = *p;
    }
  }
  REQUIRE(original.has_value());

  auto saved = at::render::loadPreset(exported);
  REQUIRE_MESSAGE(saved.has_value(), saved.error().message);
  CHECK(saved->name == "my_cochlea");
  CHECK(saved->t == 1.0f);
  CHECK(saved->dataTf.size() == original->dataTf.size() + 1);
  bool found = false;
  for (const auto& p : saved->dataTf)
    if (p.x == 777) {
      found = true;
      CHECK(p.rgba == at::render::Rgba{1, 0, 0, 0.9f});
    }
  CHECK(found);
  CHECK(saved->distanceTf == original->distanceTf);  // not edited
  CHECK(saved->weightRule == original->weightRule);

  auto db = at::db::Database::open(dbPath.string());
  REQUIRE(db.has_value());
  auto stored = at::db::findPreset(*db, "my_cochlea");
  REQUIRE(stored.has_value());
  REQUIRE(stored->has_value());
  auto fromDb = at::render::parsePreset((*stored)->json, "stored my_cochlea");
  REQUIRE_MESSAGE(fromDb.has_value(), fromDb.error().message);
  CHECK(fromDb->dataTf == saved->dataTf);

  auto a = at::readPng(before.string()), b = at::readPng(after.string());
  REQUIRE(a);
  REQUIRE(b);
  const double diff = viewDifference(*a, *b);
  MESSAGE("mean view difference after the edit: " << diff);
  CHECK(diff > 2.0);
}
