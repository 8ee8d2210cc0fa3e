// InVesalius projects through the command line, as a user would: info, slice, wdt and render open
// a .inv3 like any volume file; a broken one fails with one line; the built-in name `skull` opens
// the fetched head CT or says how to fetch it.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>

#include "inv3_test_files.h"
#include "test_support.h"
#include "volume/image_file.h"
#include "volume/inv3_io.h"
#include "volume/known_scans.h"
#include "volume/nrrd_io.h"
#include "volume/png_image.h"

using namespace at;

namespace {

std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

void checkOneLineError(const test::CommandResult& r, const std::string& mustMention) {
  CHECK(r.exitCode != 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find(mustMention) != std::string::npos);
}

// A 24x20x16 project: a bone shell (1000 HU) around soft tissue (40 HU) in air, 1 x 1 x 1.5 mm.
constexpr int kNx = 24, kNy = 20, kNz = 16;
bool insideBall(int x, int y, int z, double radius) {
  const double dx = x - 11.5, dy = y - 9.5, dz = (z - 7.5) * 1.5;
  return dx * dx + dy * dy + dz * dz < radius * radius;
}

void writeHeadProject(const std::filesystem::path& path) {
  test::Inv3Plist plist;
  plist.top["spacing"] = "<array><real>1.0</real><real>1.0</real><real>1.5</real></array>";
  plist.matrix["shape"] = "<array><integer>16</integer><integer>20</integer><integer>24</integer></array>";
  std::string matrix;
  for (int z = 0; z < kNz; ++z)
    for (int y = 0; y < kNy; ++y)
      for (int x = 0; x < kNx; ++x) {
        const std::int16_t hu = insideBall(x, y, z, 5) ? 40 : insideBall(x, y, z, 8) ? 1000 : -1000;
        const std::uint16_t v = std::uint16_t(hu);
        matrix.push_back(char(v & 0xff));
        matrix.push_back(char(v >> 8));
      }
  test::writeInv3(path, plist, matrix);
}

// Labels for the project's soft-tissue ball on the project's own grid, as NRRD, with names.
void writeBallLabels(const std::filesystem::path& project, const std::filesystem::path& labels,
                     const std::filesystem::path& names) {
  auto loaded = loadInv3(project.string());
  REQUIRE_MESSAGE(loaded, test::errorText(loaded));
  FloatVolume map(loaded->image.geometry, 0.0f);
  for (int z = 0; z < kNz; ++z)
    for (int y = 0; y < kNy; ++y)
      for (int x = 0; x < kNx; ++x)
        if (insideBall(x, y, z, 5)) map.at(x, y, z) = 1;
  REQUIRE(writeNrrd(labels.string(), map, ScalarKind::UInt8));
  std::ofstream(names) << "{\"1\": \"brain\"}";
}

// Sets an environment variable for one scope (the app runs as a child and inherits it).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_) ::setenv(name_, old_.c_str(), 1);
    else ::unsetenv(name_);
  }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

}  // namespace

TEST_CASE("info, slice, wdt and render open an InVesalius .inv3 like any volume file") {
  if (!test::requireAppBinary("the .inv3 command-line test")) return;
  test::TempDir dir;
  const auto project = dir / "head.inv3", labels = dir / "labels.nrrd", names = dir / "names.json";
  writeHeadProject(project);
  writeBallLabels(project, labels, names);

  auto r = test::runApp("info " + quoted(project));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("dimensions:  24x20x16") != std::string::npos);
  CHECK(r.out.find("orientation: LAS") != std::string::npos);
  CHECK(r.out.find("HU range:    -1000.0 … 1000.0") != std::string::npos);
  CHECK(r.out.find("InVesalius project (format 1), modality CT") != std::string::npos);

  const auto png = dir / "axial.png";
  r = test::runApp("slice " + quoted(project) + " --axis z --index 8 --out " + quoted(png));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  auto image = readPng(png.string());
  REQUIRE(image);
  CHECK(image->width == kNx);
  CHECK(image->height == kNy);

  const std::string withLabels = " --labels " + quoted(labels) + " --names " + quoted(names);
  r = test::runApp("wdt " + quoted(project) + " brain" + withLabels + " --converge --backend cpu");
  CHECK_MESSAGE(r.exitCode == 0, r.err);

  const auto render = dir / "render.png";
  r = test::runApp("render " + quoted(project) + " brain" + withLabels + " --mode bare --size 48x32 --out " + quoted(render));
  if (r.exitCode != 0 && r.err.find("EGL") != std::string::npos) {
    at::test::skipf("rendering the .inv3 needs EGL (%s)", r.err.c_str());
    return;
  }
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(readPng(render.string()));
}

TEST_CASE("a damaged .inv3 fails info and slice with one line naming the file") {
  if (!test::requireAppBinary("the broken .inv3 command-line test")) return;
  test::TempDir dir;
  const auto project = dir / "head.inv3";
  writeHeadProject(project);
  std::string bytes = test::readFile(project);
  std::ofstream(project, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
  checkOneLineError(test::runApp("info " + quoted(project)), project.string() + ": ");
  checkOneLineError(test::runApp("slice " + quoted(project) + " --axis z --index 1 --out " + quoted(dir / "x.png")),
                    project.string() + ": ");
}

TEST_CASE("the dataset name skull opens the fetched head CT, and says how to fetch it when absent") {
  if (!test::requireAppBinary("the skull dataset command-line test")) return;
  const KnownScan* scan = findKnownScan("skull");
  REQUIRE(scan);
  test::TempDir dir;
  {
    // An empty cache: only an installed invesalius-examples package could still provide the file.
    ScopedEnv cache("XDG_CACHE_HOME", dir.path().string());
    if (locateKnownScan(*scan)) {
      at::test::skipf("the absent-skull messages (invesalius-examples is installed at %s)", scan->packagePath.c_str());
    } else {
      const auto r = test::runApp("slice skull --axis z --index 1 --out " + quoted(dir / "x.png"));
      checkOneLineError(r, "dataset 'skull' is Cranium.inv3 from Debian's invesalius-examples package, which is not here");
      CHECK(r.err.find("scripts/fetch-scans.sh") != std::string::npos);
      checkOneLineError(test::runApp("info skull"), "apt-get install invesalius-examples");
      const auto listed = test::runApp("datasets");
      CHECK(listed.exitCode == 0);
      CHECK(listed.out.find("skull") != std::string::npos);
      CHECK(listed.out.find("not fetched") != std::string::npos);
    }
  }
  const auto path = locateKnownScan(*scan);
  if (!path) {
    at::test::skipf("opening skull needs Cranium.inv3 from Debian's invesalius-examples (run scripts/fetch-scans.sh)");
    return;
  }
  auto r = test::runApp("info skull");
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("dimensions:  256x256x108") != std::string::npos);
  CHECK(r.out.find(path->string()) != std::string::npos);
  r = test::runApp("datasets");
  CHECK(r.out.find(path->string()) != std::string::npos);
  const auto png = dir / "skull.png";
  r = test::runApp("slice skull --axis y --index 185 --out " + quoted(png));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  auto image = readPng(png.string());
  REQUIRE(image);
  // A coronal slice in square pixels of 0.957 mm: 256 columns, and 108 slices of 1.5 mm as 169 rows.
  CHECK(image->width == 256);
  CHECK(image->height == 169);
}
