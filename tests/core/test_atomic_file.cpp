// Writing files atomically: a failed or killed write keeps the old file, never leaves half of one.
#include <doctest/doctest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>

#include "core/atomic_file.h"
#include "test_support.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    char name[] = "/tmp/at-atomic-XXXXXX";
    path = ::mkdtemp(name);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

std::string readAll(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Names in `dir` other than `keep`.
std::vector<std::string> othersIn(const fs::path& dir, const std::string& keep) {
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename() != keep) out.push_back(e.path().filename().string());
  return out;
}

// A small tmpfs mounted for the test (needs root); unmounted when it dies.
struct SmallDisk {
  TempDir dir;
  bool mounted = false;
  explicit SmallDisk(const char* size) {
    const std::string options = std::string("size=") + size;
    mounted = ::geteuid() == 0 && ::mount("tmpfs", dir.path.c_str(), "tmpfs", 0, options.c_str()) == 0;
  }
  ~SmallDisk() {
    if (mounted) ::umount(dir.path.c_str());
  }
};

}  // namespace

TEST_CASE("AtomicFile_Replace_NewContentAndNoTemporaryLeft") {
  TempDir dir;
  const fs::path out = dir.path / "labels.nii.gz";
  REQUIRE(writeFileAtomically(out.string(), "old"));
  REQUIRE(writeFileAtomically(out.string(), "new content"));
  CHECK(readAll(out) == "new content");
  CHECK(othersIn(dir.path, "labels.nii.gz").empty());
}

TEST_CASE("AtomicFile_NotCommitted_OldFileKeptAndTemporaryRemoved") {
  TempDir dir;
  const fs::path out = dir.path / "a.csv";
  REQUIRE(writeFileAtomically(out.string(), "old"));
  {
    auto file = AtomicFile::create(out.string());
    REQUIRE(file);
    REQUIRE(file->write("half of the new"));
    CHECK(fs::exists(file->temporaryPath()));
  }
  CHECK(readAll(out) == "old");
  CHECK(othersIn(dir.path, "a.csv").empty());
}

TEST_CASE("AtomicFile_Link_TargetGetsTheContentAndLinkStays") {
  TempDir dir;
  REQUIRE(writeFileAtomically((dir.path / "target.png").string(), "old"));
  fs::create_symlink(dir.path / "target.png", dir.path / "link.png");
  REQUIRE(writeFileAtomically((dir.path / "link.png").string(), "new"));
  CHECK(fs::is_symlink(dir.path / "link.png"));
  CHECK(readAll(dir.path / "target.png") == "new");
}

TEST_CASE("AtomicFile_FifoDeviceOrFolder_RefusedAtOnceWithoutOpening") {
  TempDir dir;
  const fs::path fifo = dir.path / "out.nii.gz";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  // In a child with an alarm: a write that opened the FIFO would block forever (nobody reads it).
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    ::alarm(5);
    const auto a = writeFileAtomically(fifo.string(), "x");
    const auto b = writeFileAtomically("/dev/null", "x");
    const auto c = writeFileAtomically(dir.path.string(), "x");
    const bool ok = !a && a.error().message.find("FIFO") != std::string::npos && !b &&
                    b.error().message.find("device") != std::string::npos && !c &&
                    c.error().message.find("folder") != std::string::npos;
    ::_exit(ok ? 0 : 1);
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  CHECK_MESSAGE(WIFEXITED(status), "the write hung on a FIFO (killed by the alarm)");
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(fs::is_fifo(fifo));
  CHECK(othersIn(dir.path, "out.nii.gz").empty());
}

TEST_CASE("AtomicFile_MissingFolder_NamedInTheError") {
  const auto r = writeFileAtomically("/tmp/at-no-such-folder-xyz/a.png", "x");
  REQUIRE_FALSE(r);
  CHECK(r.error().message.find("at-no-such-folder-xyz") != std::string::npos);
}

TEST_CASE("AtomicFile_FullDisk_FailsNamingTheFileAndKeepsTheOldFile") {
  SmallDisk disk("64k");
  if (!disk.mounted) {
    MESSAGE("skipped: mounting a small tmpfs needs root (CI runs this as root)");
    return;
  }
  const fs::path out = disk.dir.path / "field.nrrd";
  const std::string old(10000, 'o');
  REQUIRE(writeFileAtomically(out.string(), old));
  const auto r = writeFileAtomically(out.string(), std::string(200000, 'n'));
  REQUIRE_FALSE(r);
  CHECK((r.error().kind == ErrorKind::Io));
  CHECK(r.error().message.find(out.string()) != std::string::npos);
  CHECK(readAll(out) == old);
  CHECK(othersIn(disk.dir.path, "field.nrrd").empty());
}

TEST_CASE("AtomicFile_KilledWhileWriting_OldOrNewNeverPartial") {
  TempDir dir;
  const fs::path out = dir.path / "export.csv";
  const std::string old(300000, 'o'), fresh(3000000, 'n');
  const std::uint64_t seed = test::freshSeed("AtomicFile_KilledWhileWriting");
  INFO("seed " << seed);
  std::mt19937 random{unsigned(seed)};
  // Kills land anywhere from before the first byte to after the rename: the delay is drawn over
  // 1.5 times what one whole write takes here.
  const auto writeStart = std::chrono::steady_clock::now();
  REQUIRE(writeFileAtomically(out.string(), fresh));
  const auto wholeWriteUs =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - writeStart).count();
  int sawNew = 0;
  for (int round = 0; round < 12; ++round) {
    REQUIRE(writeFileAtomically(out.string(), old));
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      // Many small writes, so that a kill lands in the middle of them.
      auto file = AtomicFile::create(out.string());
      if (!file) ::_exit(1);
      for (std::size_t at = 0; at < fresh.size(); at += 4096)
        if (!file->write(std::string_view(fresh).substr(at, 4096))) ::_exit(1);
      ::_exit(file->commit() ? 0 : 1);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(random() % std::uint64_t(1 + wholeWriteUs * 3 / 2)));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    const std::string now = readAll(out);
    CHECK_MESSAGE((now == old || now == fresh), "round " << round << ": a file of " << now.size() << " bytes");
    sawNew += now == fresh;
  }
  MESSAGE("new content complete in " << sawNew << " of 12 rounds (one write " << wholeWriteUs << " us)");
  // The next write removes what killed writers left behind.
  REQUIRE(writeFileAtomically(out.string(), "final"));
  CHECK(othersIn(dir.path, "export.csv").empty());
}
