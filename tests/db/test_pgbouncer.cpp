// Many lab machines on one class server: PostgreSQL with few connection slots and PgBouncer in
// front in transaction mode (scripts/pgbouncer.sh). The program keeps no session state, so every
// machine's writes and reads are right whichever server connection runs them; a full server
// is refused with one line that says what to do.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <latch>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "db/connection.h"
#include "db/study_store.h"
#include "pooled_postgres.h"
#include "quiz/study_protocol.h"
#include "test_databases.h"

using namespace at;

namespace {

quiz::StudyProtocol labStudy() {
  quiz::StudyProtocol p;
  p.id = "pooled_lab";
  p.title = "lab machines through PgBouncer";
  for (int s = 0; s < 13; ++s) p.structures.push_back("structure_" + std::to_string(s));
  p.conditions = {{"wdt", "WDT", "_wdt"}, {"bare", "bare", "_bare"}};
  for (const char* item : {"shape", "context", "localization", "utility"}) p.items.push_back({item, item});
  p.groups = {"medical", "non-medical"};
  p.dataset = "phantom";
  return p;
}

// A response time no decimal shortcut survives: read back exactly only when the server's float
// output is exact on whatever server connection the read ran.
double responseMsOf(int machine, int position) { return 1000.0 + machine / 7.0 + position / 3.0; }

}  // namespace

TEST_CASE("PgBouncer_TwoHundredLabMachinesOnTwentyServerSlots_NoneRefusedEveryRatingStoredExactly") {
  if (test::testingOnPostgres()) return;  // runs its own server: once is enough
  test::PooledPostgres server(20, 10);
  auto urls = test::pooledDatabase(server, "the PgBouncer test");
  if (!urls) return;
  const auto p = labStudy();
  {
    auto setup = db::openDatabase(urls->pooled);
    REQUIRE_MESSAGE(setup, (setup ? "" : setup.error().message));
    REQUIRE(db::saveStudy(*setup, p));
  }
  constexpr int kMachines = 200, kTrials = 2;
  std::vector<std::string> errors(kMachines);
  std::atomic<int> refused{0};
  std::latch start(kMachines);
  // What is tested is that the pooler queues the machines, not how fast it admits 200 logins at
  // once: that depends on the machine's load (the sanitizer suite runs this beside another test,
  // where 45 of 200 five-second connects once timed out). A refusal by the pooler (over its client
  // limit) still comes at once.
  db::OpenOptions patient;
  patient.connectTimeoutSeconds = 60;
  std::vector<std::thread> machines;
  for (int m = 0; m < kMachines; ++m)
    machines.emplace_back([&, m] {
      auto db = db::openDatabase(urls->pooled, patient);  // each machine keeps its connection, as the program does
      start.arrive_and_wait();
      if (!db) {
        ++refused;
        errors[std::size_t(m)] = db.error().message;
        return;
      }
      auto part = db::enrolOrResume(*db, p, "m" + std::to_string(m), p.groups[std::size_t(m % 2)]);
      if (!part) {
        errors[std::size_t(m)] = part.error().message;
        return;
      }
      for (int t = 0; t < kTrials; ++t)
        for (const auto& item : p.items) {
          db::RatingRecord r;
          r.position = t;
          r.item = item.id;
          r.ratingAsShown = 1 + (m + t) % 5;
          r.responseMs = responseMsOf(m, t);
          if (auto s = db::recordRating(*db, *part, r); !s) {
            errors[std::size_t(m)] = s.error().message;
            return;
          }
        }
    });
  for (auto& t : machines) t.join();
  std::string listed;
  for (const auto& e : errors)
    if (!e.empty() && listed.size() < 2000) listed += e + "\n";
  CHECK_MESSAGE(refused.load() == 0, listed);
  CHECK_MESSAGE(listed.empty(), listed);

  auto reader = db::openDatabase(urls->pooled);
  REQUIRE(reader);
  auto rows = db::studyResponseRows(*reader, p);
  REQUIRE_MESSAGE(rows, (rows ? "" : rows.error().message));
  CHECK(rows->size() == std::size_t(kMachines * kTrials) * p.items.size());
  for (const auto& r : *rows) {
    const int m = std::stoi(r.participantId.substr(1));
    CAPTURE(r.participantId);
    CHECK(r.responseMs == responseMsOf(m, r.presentationOrder - 1));
    CHECK(r.ratingAb == 1 + (m + r.presentationOrder - 1) % 5);
  }
  // Every machine got its own counterbalancing row (the writers' lock held across the pool).
  auto participants = db::studyParticipantRows(*reader, p.id);
  REQUIRE(participants);
  std::vector<int> enrolment;
  for (const auto& x : *participants) enrolment.push_back(x.enrolmentIndex);
  std::sort(enrolment.begin(), enrolment.end());
  enrolment.erase(std::unique(enrolment.begin(), enrolment.end()), enrolment.end());
  CHECK(enrolment.size() == std::size_t(kMachines));
}

TEST_CASE("PgBouncer_ServerOutOfSlots_RefusalIsOneLineSayingWhatToDoAndThePoolerTakesThemAll") {
  if (test::testingOnPostgres()) return;
  test::PooledPostgres server(10, 4);
  auto urls = test::pooledDatabase(server, "the PgBouncer test");
  if (!urls) return;
  std::vector<db::Connection> direct, pooled;
  std::optional<std::string> refusal;
  for (int i = 0; i < 15 && !refusal; ++i) {
    auto c = db::openDatabase(urls->direct);
    if (c) direct.push_back(std::move(*c));
    else refusal = c.error().message;
  }
  REQUIRE(refusal.has_value());
  CAPTURE(*refusal);
  CHECK(refusal->find('\n') == std::string::npos);
  CHECK(refusal->find("is full") != std::string::npos);
  CHECK(refusal->find("PgBouncer") != std::string::npos);
  CHECK(refusal->find("max_connections") != std::string::npos);
  direct.clear();
  for (int i = 0; i < 30; ++i) {
    auto c = db::openDatabase(urls->pooled);
    CHECK_MESSAGE(c, (c ? "" : c.error().message));
    if (c) pooled.push_back(std::move(*c));
  }
  CHECK(pooled.size() == 30);
}
