// The command line's outputs are safe to share and to keep: a full disk or a kill never leaves a
// half-written --out in place of the old one, FIFOs and devices given as paths are refused at once,
// titles and names from a course reach the terminal without escape sequences, and one damaged
// stored lesson leaves every other command working.
#include <doctest/doctest.h>

#include <sqlite3.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "test_support.h"
#include "volume/nifti_io.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// Runs a shell line in which @APP@ stands for the anatomy-tutor binary, with a 20 s limit (exit
// 124 when the command blocked until `timeout` killed it).
test::CommandResult runShell(const test::TempDir& dir, std::string line) {
  const std::string app = "timeout 20 " + quoted(test::appBinary());
  for (std::size_t at = line.find("@APP@"); at != std::string::npos; at = line.find("@APP@", at + app.size()))
    line.replace(at, 5, app);
  const fs::path out = dir / "shell.out", err = dir / "shell.err";
  const int status = std::system(("(" + line + ") >" + quoted(out) + " 2>" + quoted(err)).c_str());
  test::CommandResult r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = test::readFile(out);
  r.err = test::readFile(err);
  return r;
}

// An 8³ CT with a cube labelled 1, and seeds for it (background at a corner, label 1 inside).
void writeSmallDataset(const fs::path& dir) {
  Geometry g;
  g.dims = {8, 8, 8};
  FloatVolume ct(g, -1000.0f);
  LabelMap labels(g, 0);
  for (int k = 2; k < 6; ++k)
    for (int j = 2; j < 6; ++j)
      for (int i = 2; i < 6; ++i) ct.at(i, j, k) = 300.0f, labels.at(i, j, k) = 1;
  REQUIRE(writeNiftiFloat((dir / "ct.nii").string(), ct));
  REQUIRE(writeNiftiLabels((dir / "labels.nii").string(), labels));
  std::ofstream(dir / "seeds.json") << R"({"schema": 1, "labels": [{"value": 0, "name": "background"},
    {"value": 1, "name": "cube"}], "strokes": [{"label": 0, "points": [[0, 0, 0]]}, {"label": 1, "points": [[3, 3, 3]]}]})";
}

std::vector<std::string> namesIn(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.push_back(e.path().filename().string());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("SafeOutput_FullDisk_SegmentAndWdtOutFailAndKeepTheOldFile") {
  if (!test::requireAppBinary("full disk outputs")) return;
  test::TempDir dir;
  writeSmallDataset(dir.path());
  const fs::path disk = dir / "disk";
  fs::create_directories(disk);
  if (::geteuid() != 0 || ::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=64k") != 0) {
    at::test::skipf("mounting a 64 KiB tmpfs needs root (CI runs the tests as root)");
    return;
  }
  struct Unmount {
    fs::path path;
    ~Unmount() { ::umount2(path.c_str(), MNT_DETACH); }
  } unmount{disk};
  const std::string dataset = quoted(dir / "ct.nii") + " --labels " + quoted(dir / "labels.nii");
  // Old outputs of a first run, then the disk filled up to a few KB.
  const fs::path labels = disk / "grown.nii", field = disk / "field.nii";
  auto r = test::runApp("segment " + dataset + " --seeds " + quoted(dir / "seeds.json") + " --backend cpu --out " +
                        quoted(labels));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  const std::string oldLabels = test::readFile(labels);
  {
    std::ofstream fill(disk / "fill", std::ios::binary);
    const std::string block(1024, 'x');
    while (fill.write(block.data(), std::streamsize(block.size()))) {
    }
  }
  const auto filesBefore = namesIn(disk);
  // The fill left less than a KB: the new label map (an uncompressed .nii of 8³ uint16, 1376 bytes)
  // does not fit.
  r = test::runApp("segment " + dataset + " --seeds " + quoted(dir / "seeds.json") + " --backend cpu --out " +
                   quoted(labels));
  CHECK(r.exitCode != 0);
  CHECK(r.err.find(labels.string()) != std::string::npos);
  CHECK(r.err.find("No space left on device") != std::string::npos);
  CHECK(test::readFile(labels) == oldLabels);
  r = test::runApp("wdt phantom:16 cochlea --backend cpu --out " + quoted(field));
  CHECK(r.exitCode != 0);
  CHECK(!fs::exists(field));
  CHECK(namesIn(disk) == filesBefore);  // no temporary or partial file left
}

TEST_CASE("SafeOutput_FifoOrDevice_AsSeedsOrOut_RefusedAtOnce") {
  if (!test::requireAppBinary("FIFO paths")) return;
  test::TempDir dir;
  writeSmallDataset(dir.path());
  REQUIRE(::mkfifo((dir / "pipe").c_str(), 0600) == 0);
  fs::create_symlink("/dev/full", dir / "full.nii");  // a device behind a plausible name
  const std::string dataset = quoted(dir / "ct.nii") + " --labels " + quoted(dir / "labels.nii");
  const std::string pipe = quoted(dir / "pipe");
  struct Case {
    std::string args, mention;
  };
  const Case cases[] = {
      {"segment " + dataset + " --seeds " + pipe + " --out " + quoted(dir / "o.nii.gz"), "FIFO"},
      {"segment " + dataset + " --seeds " + quoted(dir / "seeds.json") + " --backend cpu --out " + quoted(dir / "p.nii") +
           " --names " + pipe,
       "FIFO"},
      {"wdt phantom:16 cochlea --backend cpu --out " + quoted(dir / "full.nii"), "device"},
      {"slice " + dataset + " --axis z --index 3 --out " + pipe, "FIFO"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.args);
    const auto start = std::chrono::steady_clock::now();
    const auto r = runShell(dir, "@APP@ " + c.args);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    CAPTURE(r.err);
    CHECK(r.exitCode != 0);
    CHECK(r.exitCode != 124);
    CHECK(seconds < 15);
    CHECK(r.err.find(c.mention) != std::string::npos);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  CHECK(fs::is_fifo(dir / "pipe"));
}

TEST_CASE("SafeOutput_HostileCourseTitles_NeverReachTheTerminalRaw") {
  if (!test::requireAppBinary("course titles")) return;
  test::TempDir dir;
  const std::string db = " --db " + quoted(dir / "t.db");
  const std::string evil = "Ear\x1b]0;owned\x07\x1b[2J\xe2\x80\xae" "all answers correct\xc2\x9b" "31m";
  auto r = test::runApp("course new evil --dataset phantom --title '" + evil + "' --out " + quoted(dir / "evil.json") + db);
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  r = test::runApp("course import " + quoted(dir / "evil.json") + db);  // `new --out` writes a draft only
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find('\x1b') == std::string::npos);
  for (const std::string& command : {std::string("courses"), std::string("lessons evil"), std::string("course list")}) {
    CAPTURE(command);
    r = test::runApp(command + db);
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.out.find("Ear") != std::string::npos);
    CHECK(r.out.find('\x1b') == std::string::npos);
    CHECK(r.out.find('\x07') == std::string::npos);
    CHECK(r.out.find("\xe2\x80\xae") == std::string::npos);
    CHECK(r.out.find("\xc2\x9b") == std::string::npos);
    CHECK(r.out.find("\\x1b[2J") != std::string::npos);  // shown, not acted on
  }
}

// A listing prints one row per course (lesson, study): a title that holds a line break (or a
// carriage return) shows it as \n, so it cannot put a row of its own under the others.
TEST_CASE("SafeOutput_TitlesWithLineBreaks_StayInTheirRow") {
  if (!test::requireAppBinary("titles with line breaks")) return;
  test::TempDir dir;
  const std::string db = " --db " + quoted(dir / "t.db");
  const std::string forgedRow = "forged_course            Forged title    dataset phantom      1 lesson (version 9)";
  const std::string shipped = test::runApp("courses" + db).out;  // the default courses' rows
  const auto rows = [](const std::string& text) { return std::count(text.begin(), text.end(), '\n'); };
  REQUIRE(rows(shipped) >= 1);
  for (const std::string& breakText : {std::string("\n"), std::string("\r"), std::string("\r\n"), std::string("\xe2\x80\xa8")}) {
    CAPTURE(breakText.size());
    const std::string id = "broken" + std::to_string(breakText.size()) + std::to_string(int((unsigned char)breakText[0]));
    auto r = test::runApp("course new " + id + " --dataset phantom --title 'Skull" + breakText + forgedRow + "' --out " +
                          quoted(dir / (id + ".json")) + db);
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    r = test::runApp("course import " + quoted(dir / (id + ".json")) + db);
    REQUIRE_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.out.find("\nforged_course") == std::string::npos);  // its report's line too
  }
  auto courses = test::runApp("courses" + db);
  REQUIRE_MESSAGE(courses.exitCode == 0, courses.err);
  auto list = test::runApp("course list" + db);
  REQUIRE_MESSAGE(list.exitCode == 0, list.err);
  for (const test::CommandResult* r : {&courses, &list}) {
    CAPTURE(r->out);
    CHECK(rows(r->out) == rows(shipped) + 4);  // one row per course
    CHECK(r->out.find('\r') == std::string::npos);
    CHECK(r->out.find("\nforged_course") == std::string::npos);
    CHECK(r->out.find("\xe2\x80\xa8") == std::string::npos);
    CHECK(r->out.find("Skull\\nforged_course") != std::string::npos);  // shown as an escape, in its row
  }
  auto lessons = test::runApp("lessons broken110" + db);
  REQUIRE_MESSAGE(lessons.exitCode == 0, lessons.err);
  CHECK(lessons.out.rfind("broken110 — Skull\\nforged_course", 0) == 0);
  CHECK(lessons.out.find("\nforged_course") == std::string::npos);
}

TEST_CASE("SafeOutput_DamagedLessonRow_OtherCommandsWorkWithOneWarningLine") {
  if (!test::requireAppBinary("damaged row")) return;
  test::TempDir dir;
  const fs::path path = dir / "t.db";
  const std::string db = " --db " + quoted(path);
  auto r = test::runApp("courses" + db);
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  {
    sqlite3* raw = nullptr;
    REQUIRE(sqlite3_open(path.c_str(), &raw) == SQLITE_OK);
    REQUIRE(sqlite3_exec(raw, "UPDATE questions SET json = '{broken' WHERE lesson_id = 'inner_ear'", nullptr, nullptr,
                         nullptr) == SQLITE_OK);
    CHECK(sqlite3_changes(raw) > 0);
    sqlite3_close(raw);
  }
  r = test::runApp("courses" + db);
  CHECK_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("temporal_bone") != std::string::npos);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find("lesson 'inner_ear'") != std::string::npos);
  r = test::runApp("lessons temporal_bone" + db);
  CHECK_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("\n  inner_ear ") == std::string::npos);  // not listed (others still name it as a prerequisite)
  CHECK(r.out.find("\n  middle_ear ") != std::string::npos);
  CHECK(r.err.find("lesson 'inner_ear'") != std::string::npos);
}
