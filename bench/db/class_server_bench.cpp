// class_server_bench: several lab machines writing a preference study into one store at once.
// Each client is a thread with its own connection (as a lab machine has its own program); it
// enrols its participants and records every rating and trial as the study runner does, one
// transaction each. One JSON line per client count.
//
//   class_server_bench --db LOCATION [--clients 1,3,10] [--participants-per-client 2] [--think-ms 0]
//
// LOCATION is a postgresql:// URL (a class server; bench/class_server_bench.sh starts a throwaway
// one with PostgreSQL's default durability) or a SQLite file path (every client on one file, for
// comparison). Each client count gets a fresh study id, so runs do not disturb each other.
// Reported: commits (transactions) per second over the whole run, and the latency of each commit
// as the client sees it (median, p99, max, in ms); lost = ratings written but not read back;
// refused = clients whose connection the server (or pooler) refused.
//
// --think-ms T: a lab machine's pace, a person answering — each client waits a random 0.5 T to
// 1.5 T before each commit (and up to T before its first), instead of committing back to back.
// Without it every client writes as fast as it can (the store's ceiling, not a class).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <latch>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "db/connection.h"
#include "db/study_store.h"
#include "quiz/study_protocol.h"

namespace {

using namespace at;
using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, std::size_t(q * double(values.size() - 1) + 0.5))];
}

quiz::StudyProtocol benchStudy(const std::string& id) {
  quiz::StudyProtocol p;
  p.id = id;
  p.title = "class server bench";
  for (int s = 0; s < 13; ++s) p.structures.push_back("structure_" + std::to_string(s));
  p.conditions = {{"wdt", "WDT", "_wdt"}, {"bare", "bare", "_bare"}};
  for (const char* item : {"shape", "context", "localization", "utility"}) p.items.push_back({item, item});
  p.groups = {"medical", "non-medical"};
  p.dataset = "phantom";
  return p;
}

struct ClientResult {
  std::vector<double> commitMs;
  std::vector<double> enrolMs;  // the enrolment commits alone (program-wide lock: the study's next row)
  std::string error;
  bool refused = false;
};

ClientResult runClient(const std::string& location, const quiz::StudyProtocol& p, int client, int participants,
                       double thinkMs, std::latch& start) {
  ClientResult out;
  auto db = db::openDatabase(location);
  start.arrive_and_wait();
  if (!db) {
    out.error = db.error().message;
    out.refused = true;
    return out;
  }
  std::mt19937 random(std::uint32_t(client) * 2654435761u + 1);
  const auto think = [&](double from, double to) {
    if (thinkMs <= 0) return;
    std::uniform_real_distribution<double> pause(from * thinkMs, to * thinkMs);
    std::this_thread::sleep_for(std::chrono::duration<double, std::milli>(pause(random)));
  };
  think(0, 1);
  const auto timed = [&](auto&& write) {
    think(0.5, 1.5);
    const auto t0 = Clock::now();
    auto st = write();
    out.commitMs.push_back(msSince(t0));
    if (!st && out.error.empty()) out.error = st.error().message;
    return bool(st);
  };
  for (int k = 0; k < participants && out.error.empty(); ++k) {
    const std::string id = "c" + std::to_string(client) + "-p" + std::to_string(k);
    Result<db::StudyParticipant> part = fail("not enrolled");
    if (!timed([&]() -> Status {
          part = db::enrolOrResume(*db, p, id, p.groups[std::size_t(k) % 2]);
          return part ? Status{} : tl::unexpected(part.error());
        }))
      break;
    out.enrolMs.push_back(out.commitMs.back());
    for (const auto& t : part->trials) {
      for (const auto& item : p.items) {
        db::RatingRecord r;
        r.position = t.position;
        r.item = item.id;
        r.ratingAsShown = 1 + (client + k + t.position) % 5;
        r.responseMs = 1000;
        if (!timed([&] { return db::recordRating(*db, *part, r); })) break;
      }
      if (!timed([&] { return db::recordTrialViewing(*db, *part, t.position, 3000, 2000, 1, ""); })) break;
    }
    if (out.error.empty()) timed([&] { return db::markParticipantComplete(*db, *part); });
  }
  return out;
}

std::vector<int> parseList(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ',');) out.push_back(std::stoi(part));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string location;
  std::vector<int> clientCounts = {1, 3, 10};
  int perClient = 2;
  double thinkMs = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool hasValue = i + 1 < argc;
    if (a == "--db" && hasValue) location = argv[++i];
    else if (a == "--clients" && hasValue) clientCounts = parseList(argv[++i]);
    else if (a == "--participants-per-client" && hasValue) perClient = std::stoi(argv[++i]);
    else if (a == "--think-ms" && hasValue) thinkMs = std::stod(argv[++i]);
    else {
      std::fprintf(stderr, "usage: class_server_bench --db LOCATION [--clients 1,3,10] [--participants-per-client 2] [--think-ms 0]\n");
      return 2;
    }
  }
  if (location.empty()) {
    std::fprintf(stderr, "class_server_bench: --db LOCATION is required\n");
    return 2;
  }
  auto setup = db::openDatabase(location);
  if (!setup) {
    std::fprintf(stderr, "class_server_bench: %s\n", setup.error().message.c_str());
    return 1;
  }
  const std::string runTag = std::to_string(std::chrono::system_clock::now().time_since_epoch().count());
  for (int clients : clientCounts) {
    const auto p = benchStudy("bench_" + runTag + "_" + std::to_string(clients));
    if (auto s = db::saveStudy(*setup, p); !s) {
      std::fprintf(stderr, "class_server_bench: %s\n", s.error().message.c_str());
      return 1;
    }
    std::vector<ClientResult> results(static_cast<std::size_t>(clients));
    std::latch start(clients + 1);
    std::vector<std::thread> threads;
    for (int c = 0; c < clients; ++c)
      threads.emplace_back([&, c] { results[std::size_t(c)] = runClient(location, p, c, perClient, thinkMs, start); });
    start.arrive_and_wait();
    const auto t0 = Clock::now();
    for (auto& t : threads) t.join();
    const double wallMs = msSince(t0);
    std::vector<double> all, enrol;
    std::string error;
    int refused = 0;
    for (const auto& r : results) {
      all.insert(all.end(), r.commitMs.begin(), r.commitMs.end());
      enrol.insert(enrol.end(), r.enrolMs.begin(), r.enrolMs.end());
      if (error.empty()) error = r.error;
      refused += r.refused ? 1 : 0;
    }
    std::replace(error.begin(), error.end(), '"', '\'');
    auto rows = db::studyResponseRows(*setup, p);
    const std::size_t expected = std::size_t(clients) * std::size_t(perClient) * p.structures.size() * p.items.size();
    const std::size_t stored = rows ? rows->size() : 0;
    std::printf("{\"engine\":\"%s\",\"clients\":%d,\"participants\":%d,\"commits\":%zu,\"wall_s\":%.2f,"
                "\"commits_per_s\":%.1f,\"commit_ms_p50\":%.2f,\"commit_ms_p99\":%.2f,\"commit_ms_max\":%.2f,"
                "\"enrol_ms_p50\":%.2f,\"enrol_ms_p99\":%.2f,"
                "\"think_ms\":%.0f,\"refused\":%d,\"ratings_expected\":%zu,\"ratings_stored\":%zu,\"error\":\"%s\"}\n",
                db::toString(setup->backend()), clients, clients * perClient, all.size(), wallMs / 1000,
                double(all.size()) / (wallMs / 1000), percentile(all, 0.5), percentile(all, 0.99),
                percentile(all, 1.0), percentile(enrol, 0.5), percentile(enrol, 0.99), thinkMs, refused, expected, stored, error.c_str());
    std::fflush(stdout);
    if (!error.empty() || stored != expected) return 1;
  }
  return 0;
}
