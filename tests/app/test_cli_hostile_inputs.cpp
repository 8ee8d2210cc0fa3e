// The command line facing hostile inputs and broken storage: every case is a one-line
// error naming the file and the problem, a non-zero exit status, and no lost data — or, for the
// commands that only read, a result despite a read-only database or a full disk.
#include <doctest/doctest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "test_support.h"
#include "volume/nifti_io.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

std::string bytesOf(const fs::path& path) { return test::readFile(path); }

// Runs a shell command line in which @APP@ stands for the anatomy-tutor binary.
test::CommandResult runShell(const test::TempDir& dir, std::string line) {
  const std::string app = quoted(test::appBinary());
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

// A small labelled volume (a NIfTI CT of 8³ voxels and its label map) in `dir`.
void writeSmallDataset(const fs::path& dir, int labelValue) {
  Geometry g;
  g.dims = {8, 8, 8};
  FloatVolume ct(g, -1000.0f);
  LabelMap labels(g, 0);
  for (int k = 2; k < 6; ++k)
    for (int j = 2; j < 6; ++j)
      for (int i = 2; i < 6; ++i) {
        ct.at(i, j, k) = 300.0f;
        labels.at(i, j, k) = std::uint16_t(labelValue);
      }
  REQUIRE(writeNiftiFloat((dir / "ct.nii").string(), ct));
  REQUIRE(writeNiftiLabels((dir / "labels.nii").string(), labels));
}

// Runs the rest of the test as the unprivileged user `nobody` when this process is root (root may
// write any file); returns the command prefix, or nullopt when neither applies.
std::optional<std::string> asUnprivileged() {
  if (::geteuid() != 0) return std::string();
  if (std::system("command -v setpriv >/dev/null 2>&1") != 0) return std::nullopt;
  return std::string("setpriv --reuid=65534 --regid=65534 --clear-groups ");
}

}  // namespace

TEST_CASE("info on a FIFO says so at once instead of blocking, and devices are refused") {
  if (!test::requireAppBinary("info on a FIFO")) return;
  test::TempDir dir;
  REQUIRE(::mkfifo((dir / "pipe").c_str(), 0600) == 0);
  const auto start = std::chrono::steady_clock::now();
  const auto r = runShell(dir, "timeout 20 @APP@ info " + quoted(dir / "pipe"));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CHECK(r.exitCode == 1);  // 124 when it blocked until `timeout` killed it
  CHECK(r.err == "anatomy-tutor: info: " + (dir / "pipe").string() + ": is a FIFO (named pipe), not a regular file\n");
  CHECK(seconds < 10);
  const auto names = test::runApp("info phantom:16 --labels /dev/zero");
  CHECK(names.exitCode != 0);
  const auto zero = test::runApp("info /dev/zero");
  CHECK(zero.exitCode == 1);
  CHECK(zero.err == "anatomy-tutor: info: /dev/zero: is a device, not a regular file\n");
}

TEST_CASE("A read-only database serves the commands that only read, and a write says it is read-only") {
  if (!test::requireAppBinary("read-only database")) return;
  const auto prefix = asUnprivileged();
  if (!prefix) {
    at::test::skipf("running as root without setpriv: no user for whom the database is read-only");
    return;
  }
  test::TempDir dir;
  const fs::path folder = dir / "shared";
  fs::create_directories(folder);
  const fs::path db = folder / "class.db";
  REQUIRE(test::runApp("courses --db " + quoted(db)).exitCode == 0);
  REQUIRE(test::runApp("play inner_ear --user ada --new-user --answers /dev/null --db " + quoted(db)).exitCode != 2);
  fs::permissions(dir.path(), fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                                  fs::perms::others_read | fs::perms::others_exec);
  fs::permissions(folder, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec | fs::perms::others_read |
                              fs::perms::others_exec);
  fs::permissions(db, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::others_read);
  if (::geteuid() != 0) fs::permissions(folder, fs::perms::owner_write, fs::perm_options::remove);
  const std::string before = bytesOf(db);

  const std::string on = " --db " + quoted(db);
  const auto courses = runShell(dir, *prefix + "@APP@ courses" + on);
  CHECK_MESSAGE(courses.exitCode == 0, courses.err);  // once: "cannot read the schema version: attempt to write a readonly database"
  CHECK(courses.out.find("temporal_bone") != std::string::npos);
  const auto lessons = runShell(dir, *prefix + "@APP@ lessons temporal_bone" + on);
  CHECK_MESSAGE(lessons.exitCode == 0, lessons.err);
  CHECK(lessons.out.find("inner_ear") != std::string::npos);
  const auto progress = runShell(dir, *prefix + "@APP@ progress --user ada" + on);
  CHECK_MESSAGE(progress.exitCode == 0, progress.err);
  const auto datasets = runShell(dir, *prefix + "@APP@ datasets" + on);
  CHECK_MESSAGE(datasets.exitCode == 0, datasets.err);

  const auto play = runShell(dir, *prefix + "@APP@ play inner_ear --user bob --new-user --answers /dev/null" + on);
  CHECK(play.exitCode == 1);
  CHECK(play.err.find(db.string() + ": the database is read-only (SQLite:") != std::string::npos);
  CHECK(bytesOf(db) == before);
}

TEST_CASE("A full disk: reading commands still work, a write says the disk is full (not 'fix the line')") {
  if (!test::requireAppBinary("full disk")) return;
  test::TempDir dir;
  const fs::path disk = dir / "disk";
  fs::create_directories(disk);
  // Room for a new database and its write-ahead log while it is made (about 1 MiB together):
  // a database that could not be checkpointed would lose its log below.
  if (::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=4m") != 0) {
    at::test::skipf("cannot mount a 4 MiB tmpfs here (needs root and mount permission) to fill a disk");
    return;
  }
  struct Unmount {
    fs::path path;
    ~Unmount() { ::umount2(path.c_str(), MNT_DETACH); }
  } unmount{disk};
  const fs::path db = disk / "a.db";
  const std::string on = " --db " + quoted(db);
  REQUIRE(test::runApp("play inner_ear --user ada --new-user --answers /dev/null" + on).exitCode != 2);
  // The precondition: everything the first run wrote is in the database file itself, so removing
  // the log and shared-memory files below frees space without losing a committed page.
  const fs::path wal = db.string() + "-wal";
  REQUIRE_MESSAGE((!fs::exists(wal) || fs::file_size(wal) == 0), "the new database's log was not checkpointed");
  // Fill every byte left.
  {
    std::ofstream fill(disk / "fill", std::ios::binary);
    const std::string block(4096, '\0');
    while (fill.write(block.data(), std::streamsize(block.size()))) {
    }
  }
  fs::remove(db.string() + "-wal");
  fs::remove(db.string() + "-shm");
  const std::string before = bytesOf(db);

  const auto lessons = test::runApp("lessons temporal_bone" + on);
  CHECK_MESSAGE(lessons.exitCode == 0, lessons.err);
  CHECK(lessons.out.find("inner_ear") != std::string::npos);

  test::TempDir answers;
  {
    std::ofstream(answers / "a.jsonl") << "{\"choice\": 0}\n";
  }
  const auto play = test::runApp("play inner_ear --user ada --answers " + quoted(answers / "a.jsonl") + on);
  CHECK(play.exitCode == 1);
  CAPTURE(play.err);
  CHECK(play.err.find(db.string() + ": the disk is full (SQLite: ") != std::string::npos);
  CHECK(play.err.find("free some space and run the command again") != std::string::npos);
  CHECK(play.err.find("fix the line") == std::string::npos);
  CHECK(play.err.find("a.jsonl:1") == std::string::npos);
  CHECK(bytesOf(db) == before);
}

TEST_CASE("Two study runs for one participant: the earlier is refused once the later resumes, naming it") {
  if (!test::requireAppBinary("concurrent study runs")) return;
  test::TempDir dir;
  const std::string on = " --db " + quoted(dir / "study.db");
  const std::string run = "study run wdt_vs_bare_phantom --participant P01 --group medical";
  const auto answers = [&](const fs::path& path, int rating) {
    std::ofstream out(path);
    for (int s = 0; s < 13; ++s) {
      nlohmann::json j;
      j["trial"] = s + 1;  // a resumed participant's answers must name their structure
      j["ratings"] = {{"shape", rating}, {"context", rating}, {"localization", rating}, {"utility", rating}};
      out << j.dump() << "\n";
    }
  };
  answers(dir / "first.jsonl", 1);
  answers(dir / "second.jsonl", 5);
  // The first run rates three structures, waits while the second resumes the participant and
  // finishes, then goes on. Its answers come through a FIFO that the test writes, and the second run
  // starts only once the database holds the first run's three ratings: the order is made, not
  // hoped for from sleeps (a loaded machine once started the first run more than 2 s late).
  const fs::path pipe = dir / "first.pipe";
  REQUIRE(::mkfifo(pipe.c_str(), 0600) == 0);
  std::vector<std::string> firstLines;
  {
    std::ifstream in(dir / "first.jsonl");
    for (std::string line; std::getline(in, line);) firstLines.push_back(line + "\n");
  }
  REQUIRE(firstLines.size() == 13);
  // The first run stops reading at line 4 or at the refusal, so the test's last write may meet a
  // closed pipe: SIGPIPE is ignored while the case runs (the write then fails with EPIPE).
  struct IgnoreSigpipe {
    struct sigaction saved {};
    IgnoreSigpipe() {
      struct sigaction ignore {};
      ignore.sa_handler = SIG_IGN;
      ::sigaction(SIGPIPE, &ignore, &saved);
    }
    ~IgnoreSigpipe() { ::sigaction(SIGPIPE, &saved, nullptr); }
  } ignoreSigpipe;
  test::CommandResult first;
  std::thread firstRun([&] { first = runShell(dir, "@APP@ " + run + " --answers /dev/stdin" + on + " <" + quoted(pipe)); });
  // Ends the first run's input and waits for it on every way out of this case, REQUIREs included.
  struct FinishFirst {
    int fd;
    std::thread& run;
    void now() {
      if (fd >= 0) ::close(fd);
      fd = -1;
      if (run.joinable()) run.join();
    }
    ~FinishFirst() { now(); }
  } firstInput{::open(pipe.c_str(), O_WRONLY), firstRun};  // open returns once the shell opened it
  REQUIRE(firstInput.fd >= 0);
  const auto send = [&](std::size_t from, std::size_t to) {
    for (std::size_t i = from; i < to; ++i)
      REQUIRE(::write(firstInput.fd, firstLines[i].data(), firstLines[i].size()) == ssize_t(firstLines[i].size()));
  };
  send(0, 3);
  const auto firstRatings = [&]() -> std::int64_t {
    std::error_code ec;
    if (fs::file_size(dir / "study.db", ec) == 0 || ec) return 0;
    auto db = db::Database::open((dir / "study.db").string());
    if (!db) return 0;  // still being created by the first run: asked again
    auto s = db->prepare("SELECT count(*) FROM study_ratings WHERE participant_id = 'P01'");
    if (!s) return 0;
    auto row = s->step();
    return row && *row ? s->int64(0) : 0;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (firstRatings() < 3 * 4 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  REQUIRE(firstRatings() == 3 * 4);  // three structures of four items, and no more
  const auto second = test::runApp(run + " --answers " + quoted(dir / "second.jsonl") + on);
  std::string rest;
  for (std::size_t i = 3; i < firstLines.size(); ++i) rest += firstLines[i];
  [[maybe_unused]] const ssize_t restWritten = ::write(firstInput.fd, rest.data(), rest.size());
  firstInput.now();
  CHECK_MESSAGE(second.exitCode == 0, second.err);
  CHECK(first.exitCode == 1);  // it once printed success and overwrote the second run's ratings
  CHECK(first.err.find("participant 'P01' was resumed by another session (session 2) after this one (session 1) began") !=
        std::string::npos);

  // Structures 1-3 keep the first run's ratings (as shown: 1), the rest the second's (5).
  const auto exported = test::runApp("study export wdt_vs_bare_phantom --out " + quoted(dir / "out") + on);
  REQUIRE_MESSAGE(exported.exitCode == 0, exported.err);
  // Columns: participant, group, session, structure, item, rating as shown (A/B), rating, A condition,
  // presentation order (1-based), …
  std::ifstream csv(dir / "out" / "responses_long.csv");
  std::string header, line;
  std::getline(csv, header);
  int rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    CAPTURE(line);
    std::vector<std::string> cells;
    std::stringstream fields(line);
    for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
    REQUIRE(cells.size() > 8);
    const int order = std::stoi(cells[8]);
    CHECK(std::stoi(cells[5]) == (order <= 3 ? 1 : 5));
  }
  CHECK(rows == 13 * 4);
  const auto status = test::runApp("study status wdt_vs_bare_phantom" + on);
  CHECK(status.out.find("52/52 ratings  complete") != std::string::npos);
}

TEST_CASE("An imported file replaced on the same grid is refused by checksum until imported again") {
  if (!test::requireAppBinary("imported file checksums")) return;
  test::TempDir dir;
  writeSmallDataset(dir.path(), 1);
  const std::string on = " --db " + quoted(dir / "d.db");
  const auto imported = test::runApp("import --volume " + quoted(dir / "ct.nii") + " --labels " + quoted(dir / "labels.nii") +
                                     " --name box" + on);
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  REQUIRE(test::runApp("structures box" + on).exitCode == 0);

  writeSmallDataset(dir.path(), 2);  // another label map on the same grid
  const auto changed = test::runApp("structures box" + on);
  CHECK(changed.exitCode == 1);  // it once listed the new labels as if they were the imported ones
  CHECK(changed.err.find("dataset 'box': its labels " + (dir / "labels.nii").string() + " has changed since it was imported") !=
        std::string::npos);
  CHECK(test::runApp("wdt box label_2" + on).exitCode == 1);

  const std::string reimport = "anatomy-tutor import --volume " + (dir / "ct.nii").string() + " --labels " +
                               (dir / "labels.nii").string() + " --name box --replace";
  REQUIRE(changed.err.find(reimport) != std::string::npos);
  const auto again = test::runApp(reimport.substr(std::string("anatomy-tutor ").size()) + on);
  REQUIRE_MESSAGE(again.exitCode == 0, again.err);
  const auto listed = test::runApp("structures box" + on);
  CHECK(listed.exitCode == 0);
  CHECK(listed.out.find("label_2") != std::string::npos);
}

TEST_CASE("Names from label files reach the terminal without escape sequences or line breaks") {
  if (!test::requireAppBinary("printable names")) return;
  test::TempDir dir;
  writeSmallDataset(dir.path(), 1);
  std::ofstream(dir / "names.json") << R"({"1": "liver\u001b[2J\u001b[31m\nFAKE LINE"})";
  const auto r = test::runApp("structures " + quoted(dir / "ct.nii") + " --labels " + quoted(dir / "labels.nii") +
                              " --names " + quoted(dir / "names.json"));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find('\x1b') == std::string::npos);
  CHECK(r.out.find("\nFAKE LINE") == std::string::npos);
  CHECK(r.out.find("Liver\\x1b[2J\\x1b[31m\\nFAKE LINE") != std::string::npos);
  const auto info = test::runApp("info " + quoted(dir / "labels.nii") + " --names " + quoted(dir / "names.json"));
  CHECK(info.out.find('\x1b') == std::string::npos);
}

TEST_CASE("render with a preset holding 1e309 reports the file, line and field, exit 1, not an internal error") {
  if (!test::requireAppBinary("preset with 1e309")) return;
  test::TempDir dir;
  std::ofstream(dir / "cochlea_wdt.json") << "{\n  \"mode\": \"wdt\",\n  \"alpha\": 1e309\n}\n";
  const auto r = test::runApp("render phantom:32 cochlea --mode wdt --presets " + quoted(dir.path()) + " --out " +
                              quoted(dir / "x.png"));
  CHECK(r.exitCode == 1);  // 2 and "internal error: [json.exception.out_of_range.406]" before
  CHECK(r.err == "anatomy-tutor: render: " + (dir / "cochlea_wdt.json").string() +
                     ": line 3, column 17, field 'alpha': number 1e309 is out of range (beyond ±1.8e308)\n");
}
