// Small files that ask for unbounded work: a main.plist nested 60,000 or 100,000 levels (XML,
// binary; as deep as the 1 MiB main.plist cap lets through) that would overflow libplist's stack, an .inv3 with thousands of members or 100 KB member names
// before main.plist, a course package of whitespace-padded presets. Each is refused with one line
// by a child `anatomy-tutor` whose peak memory is measured (ru_maxrss) and must stay under 200 MB.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "course_import_fixtures.h"
#include "inv3_test_files.h"
#include "package_forgery.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

constexpr long kPeakLimitKib = 200 * 1024;

void checkRefusedSmallAndQuick(const test::MeasuredRun& r, const std::string& mention, const char* what) {
  MESSAGE(what << ": exit " << r.exitCode << ", peak " << r.peakKib / 1024 << " MiB, " << r.seconds << " s");
  CHECK(r.exitCode == 1);  // a refusal, not a signal (SIGSEGV, SIGKILL by the OOM killer)
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK_MESSAGE(r.err.find(mention) != std::string::npos, r.err);
  CHECK(r.peakKib < kPeakLimitKib);
}

}  // namespace

TEST_CASE("ImportBombs_TheMeasuredPeakIsTheProgramsNotTheTestProcesss") {
  if (!test::requireAppBinary("import bombs")) return;
  const long small = test::runAppMeasured({"--version"}).peakKib;
  // 400 MiB touched and held while the program runs (as the whole suite in one process holds its
  // volumes and windows): still the program's own few MiB.
  std::vector<char> held(std::size_t(400) << 20);
  volatile char* pages = held.data();  // stores the compiler must keep
  for (std::size_t i = 0; i < held.size(); i += 4096) pages[i] = 1;
  const test::MeasuredRun beside = test::runAppMeasured({"--version"});
  MESSAGE("anatomy-tutor --version: peak " << small / 1024 << " MiB; beside a test holding 400 MiB "
                                           << beside.peakKib / 1024 << " MiB");
  CHECK(beside.exitCode == 0);
  CHECK(small > 0);
  CHECK(beside.peakKib < small + 64 * 1024);
}

TEST_CASE("ImportBombs_DeeplyNestedPlist_IsOneLineNotAStackOverflow") {
  if (!test::requireAppBinary("import bombs")) return;
  test::TempDir dir("at-bombs");
  const std::string matrix = test::inv3Matrix();
  using Members = std::vector<test::TarMember>;
  test::writeTar(dir / "deep-xml.inv3", Members{{"p/main.plist", test::deepXmlPlist(60000)}, {"p/matrix.dat", matrix}});
  test::writeTar(dir / "deep-binary.inv3", Members{{"p/main.plist", test::deepBinaryPlist(100000)}, {"p/matrix.dat", matrix}});
  for (const char* file : {"deep-xml.inv3", "deep-binary.inv3"}) {
    CAPTURE(file);
    CHECK(fs::file_size(dir / file) < 1024 * 1024);
    checkRefusedSmallAndQuick(test::runAppMeasured({"info", (dir / file).string()}), "nests more than 64 levels", file);
    checkRefusedSmallAndQuick(test::runAppMeasured({"import", "--volume", (dir / file).string(), "--name", "deep", "--db",
                                                    (dir / "s.db").string()}),
                              "nests more than 64 levels", file);
  }
  // A plist nested as deep as a real project's still loads.
  test::writeInv3(dir / "real.inv3");
  CHECK(test::runAppMeasured({"info", (dir / "real.inv3").string()}).exitCode == 0);
}

TEST_CASE("ImportBombs_Inv3MembersBeforeMainPlist_AreCappedInCountAndNameLength") {
  if (!test::requireAppBinary("import bombs")) return;
  test::TempDir dir("at-bombs");
  std::vector<test::TarMember> longNames, many;
  for (int i = 0; i < 200; ++i) longNames.push_back({std::string(100 * 1000, 'a') + std::to_string(i), "x"});
  for (int i = 0; i < 5000; ++i) many.push_back({"m" + std::to_string(i), ""});
  for (auto* members : {&longNames, &many}) {
    members->push_back({"p/main.plist", test::Inv3Plist{}.xml()});
    members->push_back({"p/matrix.dat", test::inv3Matrix()});
  }
  test::writeTar(dir / "long-names.inv3", longNames);
  test::writeTar(dir / "many.inv3", many);
  checkRefusedSmallAndQuick(test::runAppMeasured({"info", (dir / "long-names.inv3").string()}), "bytes (at most 1024)",
                            "200 members with 100 KB names");
  checkRefusedSmallAndQuick(test::runAppMeasured({"info", (dir / "many.inv3").string()}), "more than 4096 members",
                            "5000 members");
}

TEST_CASE("ImportBombs_PaddedPresets_AreRefusedWhileStreaming") {
  if (!test::requireAppBinary("import bombs")) return;
  test::TempDir author("at-author"), student("at-student");
  const fs::path package = author / "ear.atcourse";
  test::exportEarTour(author.path(), package);
  // Presets of 16 MiB of spaces each, gzip-compressed to a few tens of KB (the package
  // held 64 of them and took 2.1 GB; 8 keep this test's own memory small).
  auto entries = test::readTar(package);
  for (int i = 0; i < 8; ++i) entries.push_back(test::TarEntry("presets/p" + std::to_string(i) + ".json", "{" + std::string(16 << 20, ' ') + "}"));
  test::rechecksum(entries);
  test::writeTar(author / "bomb.atcourse", entries, true);
  entries.clear();
  MESSAGE("bomb package: " << fs::file_size(author / "bomb.atcourse") << " bytes");
  const fs::path db = student / "s.db";
  REQUIRE(test::runApp("course list --db " + test::quotedPath(db)).exitCode == 0);
  const auto before = test::snapshotTree(student.path(), {"s.db"});
  checkRefusedSmallAndQuick(test::runAppMeasured({"course", "import", (author / "bomb.atcourse").string(), "--db", db.string()}),
                            "more than the 65536 this reader accepts", "8 presets of 16 MiB");
  CHECK(test::snapshotTree(student.path(), {"s.db"}) == before);
}
