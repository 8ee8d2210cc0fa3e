#include <doctest/doctest.h>

#include <fstream>

#include "render/preset.h"
#include "volume/phantom.h"
#include "test_support.h"

using namespace at::render;
namespace fs = std::filesystem;

namespace {
const char* kValid = R"({ "schema": 1, "name": "Semicircular canals - context", "mode": "wdt",
  "data_tf":     [ {"x": -1000, "rgba": [0,0,0,0]}, {"x": 700, "rgba": [1,1,1,0.35]} ],
  "distance_tf": [ {"x": 0.0, "rgba": [1,0.5,0,1]}, {"x": 0.6, "rgba": [1,1,1,0.4]} ],
  "alpha": 1.6, "t": 0.5, "highlight_rgb": [1,0.5,0],
  "lighting": {"alpha": 0.1, "beta": 1.0},
  "weight": {"rule": "entering", "hu_window": [-1000, 2000], "base": 0.02} })";
}

TEST_CASE("The ARCHITECTURE.md example preset loads with its values") {
  auto p = parsePreset(kValid, "example.json");
  REQUIRE_MESSAGE(p, p.error().message);
  CHECK((p->mode == RenderMode::Wdt));
  CHECK(p->dataTf.size() == 2);
  CHECK(p->dataTf[1].rgba[3] == doctest::Approx(0.35));
  CHECK(p->alpha == doctest::Approx(1.6));
  CHECK(p->lightingAlpha == doctest::Approx(0.1));
  CHECK_FALSE(p->structure.has_value());
}

TEST_CASE("Missing fields take the documented defaults") {
  auto p = parsePreset(R"({"mode": "bare"})", "min.json");
  REQUIRE(p);
  Preset expected;
  expected.mode = RenderMode::Bare;
  CHECK(*p == expected);
}

TEST_CASE("Preset round trip: load, save, load gives an equal preset") {
  at::test::TempDir dir;
  auto p = parsePreset(kValid, "example.json");
  REQUIRE(p);
  p->structure = "cochlea";
  p->view = "lateral_left";
  p->clip = std::array<float, 4>{0.1f, 0.2f, 0.3f, -4.25f};
  p->id = "example";
  p->t = 0.1234567f;
  REQUIRE(savePreset(*p, dir / "a.json"));
  auto q = loadPreset(dir / "a.json");
  REQUIRE_MESSAGE(q, q.error().message);
  CHECK(*q == *p);
  REQUIRE(savePreset(*q, dir / "b.json"));
  auto r = loadPreset(dir / "b.json");
  REQUIRE(r);
  CHECK(*r == *p);
}

TEST_CASE("Every invalid preset field is rejected with the file and field named") {
  struct Case {
    const char* json;
    const char* field;
  };
  const Case cases[] = {
      {R"({"colour": 1})", "'colour'"},
      {R"({"schema": 2})", "'schema'"},
      {R"({"schema": "1"})", "'schema'"},
      {R"({"name": 5})", "'name'"},
      {R"({"mode": "xray"})", "'mode'"},
      {R"({"data_tf": 3})", "'data_tf'"},
      {R"({"data_tf": []})", "'data_tf'"},
      {R"({"data_tf": [{"x": 0, "rgba": [0,0,0,0]}, {"x": 1, "rgba": [0,0,0,0]}, {"x": 2, "rgba": [0,0,2,0]}]})",
       "'data_tf[2].rgba' must be 4 numbers in 0..1"},
      {R"({"data_tf": [{"x": 0, "rgba": [0,0,0]}]})", "'data_tf[0].rgba'"},
      {R"({"data_tf": [{"x": "a", "rgba": [0,0,0,0]}]})", "'data_tf[0].x'"},
      {R"({"data_tf": [{"rgba": [0,0,0,0]}]})", "'data_tf[0].x'"},
      {R"({"data_tf": [{"x": 5, "rgba": [0,0,0,0]}, {"x": 5, "rgba": [0,0,0,0]}]})", "'data_tf[1].x'"},
      {R"({"data_tf": [{"x": 5, "rgba": [0,0,0,0], "w": 1}]})", "'data_tf[0].w'"},
      {R"({"distance_tf": [{"x": 1.5, "rgba": [0,0,0,0]}]})", "'distance_tf[0].x'"},
      {R"({"alpha": 0.5})", "'alpha'"},
      {R"({"alpha": "big"})", "'alpha'"},
      {R"({"t": 1.5})", "'t'"},
      {R"({"highlight_rgb": [1, 0]})", "'highlight_rgb'"},
      {R"({"lighting": 1})", "'lighting'"},
      {R"({"lighting": {"alpha": -1}})", "'lighting.alpha'"},
      {R"({"lighting": {"beta": "x"}})", "'lighting.beta'"},
      {R"({"lighting": {"gamma": 1}})", "'lighting.gamma'"},
      {R"({"weight": {"rule": "leaving"}})", "'weight.rule'"},
      {R"({"weight": {"hu_window": [2000, -1000]}})", "'weight.hu_window'"},
      {R"({"weight": {"base": -0.1}})", "'weight.base'"},
      {R"({"weight": {"kind": "uniform"}})", "'weight.kind'"},
      {R"({"id": ""})", "'id'"},
      {R"({"structure": 7})", "'structure'"},
      {R"({"view": "sideways"})", "'view'"},
      {R"({"clip": [0, 0, 0, 1]})", "'clip'"},
      {R"({"clip": [1, 0, 0]})", "'clip'"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.json);
    auto p = parsePreset(c.json, "cochlea_wdt.json");
    REQUIRE_FALSE(p);
    CHECK(p.error().message.find("cochlea_wdt.json: field ") == 0);
    CHECK(p.error().message.find(c.field) != std::string::npos);
  }
  auto notJson = parsePreset("{", "broken.json");
  REQUIRE_FALSE(notJson);
  CHECK(notJson.error().message.find("broken.json") == 0);
}

TEST_CASE("The preset library lists a folder and falls back to the mode's default preset") {
  at::test::TempDir dir;
  Preset p;
  p.mode = RenderMode::Outline;
  REQUIRE(savePreset(p, dir / "default_outline.json"));
  p.mode = RenderMode::Wdt;
  REQUIRE(savePreset(p, dir / "cochlea_wdt.json"));
  PresetLibrary lib(dir.path());
  auto ids = lib.list();
  REQUIRE(ids);
  CHECK(*ids == std::vector<std::string>{"cochlea_wdt", "default_outline"});
  auto wdt = lib.forStructure("cochlea", RenderMode::Wdt);
  REQUIRE(wdt);
  CHECK(wdt->id == std::optional<std::string>("cochlea_wdt"));
  auto outline = lib.forStructure("cochlea", RenderMode::Outline);
  REQUIRE(outline);
  CHECK((outline->mode == RenderMode::Outline));
  CHECK_FALSE(lib.forStructure("cochlea", RenderMode::Fuzzy));
}

TEST_CASE("Every shipped preset in data/presets loads") {
  PresetLibrary lib(at::test::sourceDir() / "data" / "presets");
  auto ids = lib.list();
  REQUIRE(ids);
  CHECK(ids->size() >= 6);
  for (const std::string& id : *ids) {
    auto p = lib.load(id);
    CHECK_MESSAGE(p, (p ? std::string() : p.error().message));
  }
  for (RenderMode m : allRenderModes()) CHECK(lib.forStructure("no_such_structure", m));
}

TEST_CASE("Every phantom structure ships a WDT-context and a bare preset made for it") {
  PresetLibrary lib(at::test::sourceDir() / "data" / "presets");
  for (const at::Structure& s : at::phantomStructures()) {
    CAPTURE(s.id);
    auto wdt = lib.load(s.id + "_wdt");
    REQUIRE_MESSAGE(wdt, wdt.error().message);
    CHECK((wdt->mode == RenderMode::Wdt));
    CHECK(wdt->structure == std::optional<std::string>(s.id));
    auto bare = lib.load(s.id + "_bare");
    REQUIRE_MESSAGE(bare, bare.error().message);
    CHECK((bare->mode == RenderMode::Bare));
    CHECK(bare->structure == std::optional<std::string>(s.id));
  }
}

TEST_CASE("A number beyond the range of a double is an error naming the file, line and field") {
  // nlohmann-json throws out_of_range for 1e309; the reader once caught only parse_error, so the
  // exception escaped every caller (the desktop had no handler below main).
  auto p = parsePreset("{\"mode\": \"wdt\",\n \"alpha\": 1e309}", "cochlea_wdt.json");
  REQUIRE_FALSE(p);
  CHECK(p.error().message ==
        "cochlea_wdt.json: line 2, column 16, field 'alpha': number 1e309 is out of range (beyond ±1.8e308)");
  auto deep = parsePreset("{\"data_tf\": [{\"x\": 0, \"rgba\": [0, 0, 0, 2e308]}]}", "deep.json");
  REQUIRE_FALSE(deep);
  CAPTURE(deep.error().message);
  CHECK(deep.error().message.find("deep.json: line 1, column 46, field 'data_tf[0].rgba[3]': number 2e308") == 0);
}

TEST_CASE("One broken preset in a library affects only the structures that use it") {
  at::test::TempDir dir;
  Preset p;
  p.mode = RenderMode::Wdt;
  REQUIRE(savePreset(p, dir / "default_wdt.json"));
  REQUIRE(savePreset(p, dir / "stapes_wdt.json"));
  {
    std::ofstream broken(dir / "cochlea_wdt.json");
    broken << "{\"schema\": 1, \"alpha\": 1e309}\n";
  }
  PresetLibrary lib(dir.path());
  auto cochlea = lib.forStructure("cochlea", RenderMode::Wdt);
  REQUIRE_FALSE(cochlea);
  CHECK(cochlea.error().message.find((dir / "cochlea_wdt.json").string() + ": line 1, column 29, field 'alpha'") == 0);
  CHECK(lib.forStructure("stapes", RenderMode::Wdt));
  CHECK(lib.forStructure("incus", RenderMode::Wdt));  // the default
  auto ids = lib.list();
  REQUIRE(ids);
  CHECK(ids->size() == 3);
}
