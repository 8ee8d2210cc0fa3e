// The render command run as a user would: a PNG of a structure per mode, and one-line errors.
#include <doctest/doctest.h>

#include <algorithm>
#include <string>

#include "test_support.h"
#include "volume/png_image.h"

using namespace at;

namespace {

void checkOneLineError(const test::CommandResult& r, const std::string& mustMention) {
  CHECK(r.exitCode != 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find(mustMention) != std::string::npos);
}

}  // namespace

TEST_CASE("render writes a PNG of the requested size in bare and WDT mode, unless EGL is missing") {
  test::TempDir dir;
  for (const std::string mode : {"bare", "wdt"}) {
    CAPTURE(mode);
    const std::string out = (dir / (mode + ".png")).string();
    const auto r = test::runApp("render phantom:64 cochlea --mode " + mode + " --size 48x32 --out '" + out + "'");
    if (r.exitCode != 0 && r.err.find("EGL") != std::string::npos) {
      at::test::skipf("render command needs EGL (%s)", r.err.c_str());
      return;
    }
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.out.find("wrote") != std::string::npos);
    auto png = readPng(out);
    REQUIRE(png);
    CHECK(png->width == 48);
    CHECK(png->height == 32);
    // Something is drawn: not every pixel equals the background.
    const auto bg = png->pixel(0, 0);
    bool drawn = false;
    for (int y = 0; y < 32 && !drawn; ++y)
      for (int x = 0; x < 48 && !drawn; ++x)
        drawn = !std::equal(bg, bg + 3, png->pixel(x, y));
    CHECK(drawn);
  }
}

TEST_CASE("render rejects bad arguments with one line naming the problem") {
  test::TempDir dir;
  const std::string out = " --out '" + (dir / "x.png").string() + "'";
  checkOneLineError(test::runApp("render phantom:64 cochlea --mode xray" + out), "xray");
  checkOneLineError(test::runApp("render phantom:64 nowhere --mode wdt" + out), "nowhere");
  checkOneLineError(test::runApp("render phantom:64 cochlea --mode wdt --size 10by10" + out), "--size");
  checkOneLineError(test::runApp("render phantom:64 cochlea --mode wdt --view sideways" + out), "sideways");
  checkOneLineError(test::runApp("render phantom:64 cochlea --mode wdt --clip 0,0,0,1" + out), "normal");
  checkOneLineError(test::runApp("render phantom:64 cochlea --mode wdt --t 2" + out), "--t");
  checkOneLineError(test::runApp("render phantom:64 cochlea --preset no_such_preset" + out), "no_such_preset");
  checkOneLineError(test::runApp("render phantom:64 cochlea --mode wdt --preset cochlea_wdt" + out), "exactly one");
  checkOneLineError(test::runApp("render phantom:64 cochlea --mode wdt"), "--out");
}
