// --intercept/--slope on a dataset from files: VTK's headsq NRRD stores CT numbers with air at 0
// (no rescale in its header), so it loads as plain intensities; with --intercept -1024 its values
// reach air and it becomes CT in HU (the HU grey window). Bad values are one-line errors naming the
// option; built-in datasets refuse the options.
#include <doctest/doctest.h>

#include "cli_checks.h"
#include "test_support.h"

using namespace at;

TEST_CASE("slice: --intercept -1024 turns a CT stored without its rescale into HU; bad values are refused") {
  if (!test::requireSharedData("headsq NRRD") || !test::requireAppBinary("slice --intercept")) return;
  test::TempDir dir;
  const std::string nrrd = test::sharedData("headsq/nrrd/quarter.nhdr").string();
  const std::string out = (dir / "s.png").string();
  const std::string base = "slice \"" + nrrd + "\" --axis z --index 40 --out \"" + out + "\"";
  const auto plain = test::runApp(base);
  REQUIRE(plain.exitCode == 0);
  CHECK(plain.out.find("window 400,2000") == std::string::npos);  // plain: the histogram window
  const auto hu = test::runApp(base + " --intercept -1024");
  REQUIRE_MESSAGE(hu.exitCode == 0, hu.err);
  CHECK(hu.out.find("window 400,2000") != std::string::npos);  // HU: the CT grey window
  // Forced plain keeps plain intensities (shifted) even though they reach air.
  const auto forced = test::runApp(base + " --intercept -1024 --intensity plain");
  REQUIRE(forced.exitCode == 0);
  CHECK(forced.out.find("window 400,2000") == std::string::npos);
  test::checkOneLineError(test::runApp(base + " --intercept abc"), "--intercept: 'abc' is not a number");
  test::checkOneLineError(test::runApp(base + " --slope 0"), "--slope: must not be 0");
  test::checkOneLineError(test::runApp("slice phantom:32 --axis z --index 3 --out \"" + out + "\" --slope 2"),
                          "apply to datasets from files");
}
