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

TEST_CASE("the expert panel's mode list shows each mode's own preset and keeps the edits made in a mode") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-expert-modes");
  const fs::path wdtShot = dir / "wdt.png", lightingShot = dir / "lighting.png", back = dir / "back.png";
  // The default course opens on the cochlea, whose fuzzy, lighting and unweighted presets are shipped.
  const json script = {{"actions",
                        {{{"do", "layout"}},
                         {{"do", "expert"}},
                         {{"do", "wait_field"}},
                         {{"do", "layout"}},
                         {{"do", "tf_add_point"}, {"tf", "data"}, {"x", 777}, {"rgba", {1, 0, 0, 0.9}}},
                         {{"do", "wait_field"}},
                         {{"do", "screenshot"}, {"path", wdtShot.string()}},
                         {{"do", "preset_set"}, {"mode", "lighting"}},
                         {{"do", "wait_field"}},
                         {{"do", "screenshot"}, {"path", lightingShot.string()}},
                         {{"do", "preset_set"}, {"mode", "fuzzy"}, {"t", 0.5}},
                         {{"do", "preset_set"}, {"mode", "unweighted"}},
                         {{"do", "preset_set"}, {"mode", "outline"}},
                         {{"do", "preset_set"}, {"mode", "fuzzy"}},
                         {{"do", "preset_set"}, {"mode", "wdt"}},
                         {{"do", "wait_field"}},
                         {{"do", "screenshot"}, {"path", back.string()}}}}};
  at::test::DesktopOptions options;
  options.size = std::to_string(kWidth) + "x" + std::to_string(kHeight);
  options.db = dir / "presets.db";
  const at::test::DesktopRun run = at::test::runDesktopScript(dir, script, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);

  // The panel docks beside the view instead of covering its right part.
  std::vector<json> layouts;
  for (const json& e : run.events)
    if (e.is_object() && e.value("event", "") == "layout") layouts.push_back(e);
  REQUIRE(layouts.size() == 2);
  CHECK(layouts[0]["expert_docked"] == false);
  CHECK(layouts[1]["expert_docked"] == true);
  CHECK(layouts[1]["view"]["x"].get<double>() + layouts[1]["view"]["width"].get<double>() == doctest::Approx(kWidth - kExpert));

  std::optional<at::render::Preset> started;
  std::vector<at::render::Preset> switched;
  for (const json& e : run.events) {
    if (!e.is_object() || (e.value("event", "") != "expert" && e.value("event", "") != "expert_mode")) continue;
    auto p = at::render::parsePreset(e.at("preset").dump(), "expert event");
    REQUIRE_MESSAGE(p.has_value(), p.error().message);
    if (e.value("event", "") == "expert") started = *p;
    else switched.push_back(*p);
  }
  REQUIRE(started.has_value());
  REQUIRE(switched.size() == 6);
  const at::render::RenderMode order[] = {at::render::RenderMode::Lighting, at::render::RenderMode::Fuzzy,
                                          at::render::RenderMode::Unweighted, at::render::RenderMode::Outline,
                                          at::render::RenderMode::Fuzzy, at::render::RenderMode::Wdt};
  for (std::size_t i = 0; i < switched.size(); ++i) CHECK(std::string(at::render::toString(switched[i].mode)) == at::render::toString(order[i]));

  // A mode not yet edited is the structure's own preset in that mode, as `render --mode` uses it.
  const auto shipped = [](const char* id) {
    auto p = at::render::loadPreset(at::test::sourceDir() / "data" / "presets" / (std::string(id) + ".json"));
    REQUIRE_MESSAGE(p.has_value(), p.error().message);
    return *p;
  };
  for (const auto& [got, id] : {std::pair{switched[0], "cochlea_lighting"}, std::pair{switched[1], "cochlea_fuzzy"},
                                std::pair{switched[2], "cochlea_unweighted"}}) {
    const at::render::Preset want = shipped(id);
    CAPTURE(id);
    CHECK(got.dataTf == want.dataTf);
    CHECK(got.distanceTf == want.distanceTf);
    CHECK(got.t == want.t);
    CHECK(got.lightingAlpha == want.lightingAlpha);
    CHECK(got.lightingBeta == want.lightingBeta);
  }
  // Outline has no shipped cochlea preset: the derived one, a band on the distance axis.
  CHECK(switched[3].distanceTf != started->distanceTf);
  // Switching back brings each mode's edits back: fuzzy's t, and the WDT's added data point.
  CHECK(switched[4].t == 0.5f);
  CHECK(switched[4].distanceTf == switched[1].distanceTf);
  CHECK(switched[5].dataTf.size() == started->dataTf.size() + 1);
  CHECK(std::any_of(switched[5].dataTf.begin(), switched[5].dataTf.end(), [](const auto& p) { return p.x == 777; }));
  CHECK(switched[5].distanceTf == started->distanceTf);

  // The view follows: lighting draws another image, and the WDT's comes back as it was.
  auto w = at::readPng(wdtShot.string()), l = at::readPng(lightingShot.string()), b = at::readPng(back.string());
  REQUIRE(w);
  REQUIRE(l);
  REQUIRE(b);
  const double toLighting = viewDifference(*w, *l), backAgain = viewDifference(*w, *b);
  MESSAGE("mean view difference WDT → lighting " << toLighting << ", WDT → WDT after the round " << backAgain);
  CHECK(toLighting > 2.0);
  CHECK(backAgain < 0.5);
}
