// `play` tells a class member that a locate pick her class server cannot grade (a point in mm, not
// the pixel on the question's picture) is kept there as practice, in the words the desktop uses
// too (class_practice.h); a student on her own machine, whose answers go nowhere, is not told.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "class_practice.h"
#include "db/class_server.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace at;

namespace {

// The first question of inner_ear in quiz-only mode (locate the cochlea) answered with a point in
// mm by `user`; the file ends there.
test::CommandResult pickInMm(const test::TempDir& dir, const fs::path& db, const std::string& user) {
  const fs::path answers = dir / "mm.jsonl";
  std::ofstream(answers) << "{\"point_mm\": [0, 0, 0]}\n";
  return test::runApp("play inner_ear --quiz-only --no-views --new-user --user " + user + " --answers '" +
                      answers.string() + "' --db '" + db.string() + "'");
}

}  // namespace

TEST_CASE("play tells a class member, and only her, that a locate pick in mm is kept as practice by her class server") {
  if (!fs::exists(test::appBinary())) {
    test::skipf("%s is not built", test::appBinary().c_str());
    return;
  }
  test::TempDir dir("play-class-practice");
  const fs::path db = dir / "laptop.db";
  {
    auto laptop = db::openDatabase(db.string());
    REQUIRE(laptop);
    // A server that is away: her answers wait in the outbox for it.
    REQUIRE(db::rememberMembership(*laptop, {"member", "K7M2P9QX", "postgresql://member@127.0.0.1:1/anatomy_class?connect_timeout=1",
                                             db::ClassRole::Student}));
  }
  const std::string note = std::string("(").append(app::practicePickNote()).append(")");
  auto member = pickInMm(dir, db, "member");
  INFO(member.out << member.err);
  CHECK(member.out.find("[1/6] Question (locate)") != std::string::npos);
  CHECK(member.out.find(note) != std::string::npos);
  auto solo = pickInMm(dir, db, "solo");
  INFO(solo.out << solo.err);
  CHECK(solo.out.find("[1/6] Question (locate)") != std::string::npos);
  CHECK(solo.out.find("Not quite") != std::string::npos);  // the pick was graded here all the same
  CHECK(solo.out.find("as practice") == std::string::npos);
}
