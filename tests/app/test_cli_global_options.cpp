// The global options --db, --user and --size: accepted before the command as after it, and a --db
// value that cannot be a database file refused in one line before anything is created.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_checks.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace at;

namespace {
std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }
}  // namespace

TEST_CASE("GlobalOptions_BeforeTheCommand_WorkAsAfterIt") {
  if (!test::requireAppBinary("global options")) return;
  test::TempDir dir("at-global");
  const fs::path db = dir / "g.db";
  const auto before = test::runApp("--db " + quoted(db) + " lessons");
  INFO("stderr: " << before.err);
  REQUIRE(before.exitCode == 0);
  CHECK(before.out.find("temporal_bone") != std::string::npos);
  const auto after = test::runApp("lessons --db " + quoted(db));
  REQUIRE(after.exitCode == 0);
  CHECK(after.out == before.out);
  CHECK(fs::exists(db));

  // --user before the command reaches it: the user is unknown in this database.
  test::checkOneLineError(test::runApp("--db " + quoted(db) + " --user nobody_here progress"), "unknown user 'nobody_here'");
  test::checkOneLineError(test::runApp("--user=nobody_here --db=" + quoted(db) + " progress"), "unknown user 'nobody_here'");
  // A new user made by play before the command shows in progress after it.
  const fs::path answers = dir / "none.jsonl";
  { std::ofstream(answers) << ""; }
  const auto played = test::runApp("--db " + quoted(db) + " --user ana play inner_ear --new-user --answers " + quoted(answers));
  CHECK(played.out.find("created user 'ana'") != std::string::npos);
  const auto progress = test::runApp("progress --user ana --db " + quoted(db));
  INFO("progress stderr: " << progress.err);
  CHECK(progress.exitCode == 0);
  CHECK(progress.out.rfind("ana (student", 0) == 0);
  // --size before a command that takes it.
  const fs::path png = dir / "v.png";
  const auto render = test::runApp("--size 40x30 render phantom:48 cochlea --mode bare --out " + quoted(png));
  if (render.err.find("EGL") == std::string::npos) {
    CHECK(render.exitCode == 0);
    CHECK(fs::exists(png));
  }
  test::checkOneLineError(test::runApp("--size 40 lessons --db " + quoted(db)), "option --size: '40'");
  test::checkOneLineError(test::runApp("--db"), "option --db needs a value");
}

TEST_CASE("GlobalDb_ValueItCannotUse_IsRefusedAndCreatesNothing") {
  if (!test::requireAppBinary("--db checks")) return;
  test::TempDir dir("at-global-db");
  // A folder that does not exist: no folder is made for it.
  test::checkOneLineError(test::runApp("--db " + quoted(dir / "nope" / "x.db") + " lessons"), "does not exist");
  CHECK(!fs::exists(dir / "nope"));
  test::checkOneLineError(test::runApp("courses --db " + quoted(dir / "nope" / "x.db")), "does not exist");
  CHECK(!fs::exists(dir / "nope"));
  // An existing folder is not a database file.
  test::checkOneLineError(test::runApp("--db " + quoted(dir.path()) + " courses"), "is a folder");
  // An address of a server this program cannot use is refused, and no folder named after it appears.
  const fs::path cwd = fs::current_path();
  test::checkOneLineError(test::runApp("--db mysql://class.example/anatomy lessons"), "not a database this program can use");
  CHECK(!fs::exists(cwd / "mysql:"));
  // A PostgreSQL server that does not answer: one line naming it, without its password.
  const auto unreachable = test::runApp("--db postgresql://ana:secret@127.0.0.1:1/anatomy lessons");
  test::checkOneLineError(unreachable, "cannot reach the database server postgresql://ana@127.0.0.1:1/anatomy");
  CHECK(unreachable.err.find("secret") == std::string::npos);
  CHECK(!fs::exists(cwd / "postgresql:"));
  // An option where the value should be.
  test::checkOneLineError(test::runApp("lessons --db --user"), "is an option");
  // Before a command that never reads the database, the value is still checked.
  test::checkOneLineError(test::runApp("--db " + quoted(dir / "nope" / "x.db") + " structures phantom:32"), "does not exist");
}

TEST_CASE("GlobalOptions_AloneWithoutCommand_GoToTheDesktop") {
  if (!test::requireAppBinary("desktop options")) return;
  test::TempDir dir("at-global-desk");
  // With no display in the test environment the desktop says so in one line; the options were
  // accepted (a bad one would be named instead).
  const auto r = test::runApp("desktop --db " + quoted(dir / "d.db") + " --user ana --size 800x600 --frame-budget 50 --help");
  CHECK(r.exitCode == 0);
  CHECK(r.out.find("usage: anatomy-tutor [desktop]") != std::string::npos);
  test::checkOneLineError(test::runApp("--size 100x100 --ui-script x.json"), "at least 400x300");
  test::checkOneLineError(test::runApp("desktop --frame-budget fast"), "--frame-budget");
}
