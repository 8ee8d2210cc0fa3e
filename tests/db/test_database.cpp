// The storage layer on SQLite and (AT_TEST_BACKEND=postgres) PostgreSQL: opening, migrations from
// every version, refusal of newer databases, RAII transactions, verbatim storage through bound
// parameters, concurrent writers, error kinds, checksums.
#include <doctest/doctest.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <latch>
#include <set>
#include <thread>
#include <tuple>

#include "db/checksum.h"
#include "db/course_store.h"
#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/dataset_store.h"
#include "schema.h"
#include "lessons/course_json.h"
#include "lessons/lesson_engine.h"
#include "lessons/scheduling.h"
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"

namespace fs = std::filesystem;
using namespace at;
using namespace at::db;

namespace {

std::string readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

using test::schemaOf;

std::int64_t countRows(Database& db, const std::string& table) {
  auto s = db.prepare("SELECT count(*) FROM " + table);
  REQUIRE(s);
  REQUIRE(*s->step());
  return s->int64(0);
}

DatasetRecord sampleRecord(const std::string& name) {
  DatasetRecord r;
  r.name = name;
  r.species = "dog";
  r.volumePath = "/data/ct.nii.gz";
  r.volumeChecksum = "sha256:" + std::string(64, 'a');
  r.geometry.dims = {4, 5, 6};
  r.geometry.spacingMm = {0.5, 0.75, 2.0};
  r.geometry.originMm = {-10, 20.5, 30};
  r.orientation = "LPS";
  return r;
}

}  // namespace

TEST_CASE("An empty database is migrated to the newest schema version (SQLite: WAL mode, foreign keys on)") {
  test::TempDir dir;
  auto db = Database::open(test::freshDatabase(dir, "a.db"));
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  CHECK(*db->schemaVersion() == latestSchemaVersion());
  if (db->backend() == Backend::Sqlite) {
    auto mode = db->prepare("PRAGMA journal_mode");
    REQUIRE(*mode->step());
    CHECK(mode->text(0) == "wal");
    auto fk = db->prepare("PRAGMA foreign_keys");
    REQUIRE(*fk->step());
    CHECK(fk->integer(0) == 1);
  }
  for (const char* table : {"datasets", "structures", "presets", "courses", "lessons", "lesson_prerequisites",
                            "steps", "questions", "users", "attempts", "responses", "leitner_progress", "user_ability",
                            "question_stats", "review_responses", "memory_states", "review_log"})
    CHECK_MESSAGE(countRows(*db, table) == 0, table);
}

TEST_CASE("Migrations are numbered consecutively from 1") {
  const auto& all = migrations();
  REQUIRE(!all.empty());
  for (std::size_t i = 0; i < all.size(); ++i) CHECK(all[i].version == int(i + 1));
  CHECK(latestSchemaVersion() == int(all.size()));
}

TEST_CASE("A database at every earlier version migrates to the same schema as a fresh one and keeps its rows") {
  test::TempDir dir;
  auto fresh = Database::open(test::freshDatabase(dir, "fresh.db"));
  REQUIRE(fresh);
  const auto reference = schemaOf(*fresh);

  for (int from = 0; from < latestSchemaVersion(); ++from) {
    CAPTURE(from);
    const std::string path = test::freshDatabase(dir, "v" + std::to_string(from) + ".db");
    {
      OpenOptions options;
      options.targetVersion = from;
      auto old = Database::open(path, options);
      REQUIRE(old);
      CHECK(*old->schemaVersion() == from);
      if (from >= 1) REQUIRE(registerDataset(*old, sampleRecord("kept"), {}));
      if (from >= 2) REQUIRE(storeCourse(*old, test::toyCourse(), "v" + std::to_string(from)));
      if (from >= 3) {  // a learner's history: a user, an attempt, an answer and its progress
        REQUIRE(old->exec("INSERT INTO users (id, name) VALUES (7, 'kept-learner');"
                          "INSERT INTO attempts (id, user_id, lesson_id, mode, started_at) VALUES (3, 7, 'toy.ossicles', 'guided', 100);"
                          "INSERT INTO responses (attempt_id, step_index, question_id, structure, answer, correct, score,"
                          " latency_ms, answered_at) VALUES (3, 1, 'toy.ossicles.name_stapes', 'stapes', '{\"text\":\"stapes\"}', 1, 1, 500, 110);"
                          ""));
        // Its progress: a Leitner box before FSRS (schema 6), a memory state since.
        REQUIRE(old->exec(from < 6 ? "INSERT INTO progress VALUES (7, 'stapes', 2, 200000, 1, 1, 110);"
                                   : "INSERT INTO memory_states (user_id, structure, phase, stability, difficulty, due_at,"
                                     " last_review_at, reviews, answered, correct)"
                                     " VALUES (7, 'stapes', 'review', 2.0, 2.1, 200000, 110, 1, 1, 1);"));
      }
    }
    auto db = Database::open(path);
    REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
    CHECK(*db->schemaVersion() == latestSchemaVersion());
    CHECK(schemaOf(*db) == reference);
    if (from >= 1) {
      auto kept = findDataset(*db, "kept");
      REQUIRE(kept);
      REQUIRE(kept->has_value());
      CHECK((*kept)->geometry.spacingMm[1] == doctest::Approx(0.75));
    }
    if (from >= 2) {
      SqlCurriculumRepository repo(*db, test::toyBuiltin());
      auto course = repo.course("toy");
      REQUIRE(course);
      CHECK(lessons::courseToJson(*course) == lessons::courseToJson(test::toyCourse()));
    }
    if (from >= 3) {
      SqlProgressRepository progress(*db);
      auto responses = progress.responses(3);
      REQUIRE(responses);
      REQUIRE(responses->size() == 1);
      CHECK((*responses)[0].answer.text == std::optional<std::string>("stapes"));
      auto p = progress.progress(7, "stapes");
      REQUIRE(p);
      REQUIRE(p->has_value());
      // The Leitner box 2 became an FSRS memory state keeping its due time (migration 6).
      CHECK(((*p)->memory.phase == lessons::MemoryPhase::Review));
      CHECK((*p)->memory.stability == doctest::Approx(2.0));
      CHECK((*p)->memory.due == 200000);
      auto log = progress.reviewLog(7);
      REQUIRE(log);
      REQUIRE(log->size() == (from < 6 ? 1u : 0u));  // rebuilt from the answers by migration 6
      if (from < 6) CHECK((*log)[0].rebuilt);
    }
    // The newest migration's table works on the migrated file: a review answer of the kept
    // learner (or a new one) is recorded and read back.
    std::int64_t learner = 7;
    if (from < 3) {
      SqlUserRepository users(*db);
      auto created = users.createUser("new-learner", lessons::Role::Student, "");
      REQUIRE(created);
      learner = created->id;
    }
    SqlProgressRepository progress(*db);
    lessons::ReviewRecord review;
    review.response.userId = learner;
    review.response.questionId = "toy.ossicles.name_stapes";
    review.response.structureId = "stapes";
    review.response.answer.text = "stapes";
    review.response.correct = true;
    review.response.answeredAt = 300000;
    review.update.progress = {.userId = learner,
                              .structureId = "stapes",
                              .memory = lessons::Fsrs().review({}, lessons::Rating::Good, 300000)};
    review.update.progress.answered = 1;
    review.update.progress.correct = 1;
    auto recorded = progress.recordReviewAnswer(review);
    REQUIRE_MESSAGE(recorded, (recorded ? "" : recorded.error().message));
    CHECK(progress.reviewResponses(learner)->size() == 1);
  }
}

TEST_CASE("The newest migration adds the review responses table to a version-4 database") {
  REQUIRE(latestSchemaVersion() >= 5);
  CHECK(migrations()[4].summary.find("review") != std::string_view::npos);
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "v4.db");
  {
    OpenOptions options;
    options.targetVersion = 4;
    auto old = Database::open(path, options);
    REQUIRE(old);
    CHECK(!test::tableExists(*old, "review_responses"));
  }
  auto db = Database::open(path);
  REQUIRE(db);
  CHECK(*db->schemaVersion() == latestSchemaVersion());
  CHECK(test::tableExists(*db, "review_responses"));
}

TEST_CASE("Leitner progress of a version-5 database becomes FSRS memory states keeping its schedule") {
  REQUIRE(latestSchemaVersion() >= 6);
  CHECK(migrations()[5].summary.find("FSRS") != std::string_view::npos);
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "v5.db");
  {
    // What the Leitner program (schema 5) left: boxes 1 (never right, and right once before),
    // 2, 4 and 5, lesson answers and review answers.
    OpenOptions options;
    options.targetVersion = 5;
    auto old = Database::open(path, options);
    REQUIRE(old);
    REQUIRE(old->exec(
        "INSERT INTO users (id, name) VALUES (1, 'lea'), (2, 'max');"
        "INSERT INTO attempts (id, user_id, lesson_id, mode, started_at) VALUES (1, 1, 'l', 'guided', 100);"
        "INSERT INTO responses (attempt_id, step_index, question_id, structure, answer, correct, score, latency_ms,"
        " answered_at) VALUES (1, 0, 'q.a', 'cochlea', '{\"text\":\"x\"}', 0, 0, 900, 110),"
        " (1, 1, 'q.b', 'stapes', '{\"order\":[\"a\"]}', 0, 0.5, 800, 120),"
        " (1, 2, 'q.c', 'incus', '{\"choice\":1}', 1, 1, 700, 130);"
        "INSERT INTO review_responses (user_id, question_id, structure, answer, correct, score, latency_ms, answered_at)"
        " VALUES (1, 'q.c', 'incus', '{\"choice\":1}', 1, 1, 600, 115), (2, 'q.a', 'cochlea', '{\"text\":\"y\"}', 1, 1, 500, 140);"
        "INSERT INTO progress VALUES (1, 'cochlea', 1, 710, 1, 0, 110), (1, 'stapes', 1, 720, 3, 1, 120),"
        " (1, 'incus', 4, 130 + 8 * 86400, 5, 4, 130), (2, 'cochlea', 5, 140 + 16 * 86400, 6, 6, 140),"
        " (2, 'vestibule', 2, 999, 0, 0, 0);"));
  }
  auto db = Database::open(path);
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  SqlProgressRepository progress(*db);
  const auto state = [&](std::int64_t user, const char* structure) {
    auto p = progress.progress(user, structure);
    REQUIRE(p);
    REQUIRE(p->has_value());
    return **p;
  };
  const lessons::Fsrs fsrs;
  // Box 1, never right: Learning, the stability of a first Again, the difficulty of a first Again.
  const auto cochlea = state(1, "cochlea");
  CHECK((cochlea.memory.phase == lessons::MemoryPhase::Learning));
  CHECK(cochlea.memory.stability == doctest::Approx(fsrs.initialStability(lessons::Rating::Again)));
  CHECK(cochlea.memory.difficulty == doctest::Approx(fsrs.initialDifficulty(lessons::Rating::Again)));
  CHECK(cochlea.memory.due == 710);
  CHECK(cochlea.memory.lastReview == 110);
  // Box 1 after a right answer: Relearning; two of three wrong: D two thirds of the way to D0(Again).
  const auto stapes = state(1, "stapes");
  CHECK((stapes.memory.phase == lessons::MemoryPhase::Relearning));
  const double good = fsrs.initialDifficulty(lessons::Rating::Good), again = fsrs.initialDifficulty(lessons::Rating::Again);
  CHECK(stapes.memory.difficulty == doctest::Approx(good + (again - good) * 2.0 / 3.0));
  // Box 4: Review, stability 8 days, so FSRS schedules the next interval as the box did.
  const auto incus = state(1, "incus");
  CHECK((incus.memory.phase == lessons::MemoryPhase::Review));
  CHECK(incus.memory.stability == doctest::Approx(8.0));
  CHECK(fsrs.nextIntervalDays(incus.memory.stability) == 8);
  CHECK(incus.memory.due == 130 + 8 * 86400);
  CHECK(incus.answered == 5);
  CHECK(incus.correct == 4);
  CHECK(fsrs.retrievability(incus.memory, 130 + 8 * 86400) == doctest::Approx(0.9));
  const auto maxCochlea = state(2, "cochlea");
  CHECK(maxCochlea.memory.stability == doctest::Approx(16.0));
  CHECK(maxCochlea.memory.difficulty == doctest::Approx(good));
  // A row never answered is not a memory.
  CHECK(!progress.progress(2, "vestibule")->has_value());
  // The due times are the ones the Leitner boxes gave.
  CHECK(lessons::dueForReview(*progress.allProgress(1), 715).size() == 1);
  CHECK(lessons::dueForReview(*progress.allProgress(1), 720).size() == 2);

  // Every earlier answer is in the review log, in time order, rated from its grade.
  auto log = progress.reviewLog(1);
  REQUIRE(log);
  REQUIRE(log->size() == 4);
  CHECK((*log)[0].reviewedAt == 110);
  CHECK(((*log)[0].rating == lessons::Rating::Again));
  CHECK(((*log)[1].source == lessons::AnswerSource::Review));
  CHECK(((*log)[1].rating == lessons::Rating::Good));
  CHECK(((*log)[2].rating == lessons::Rating::Hard));  // half credit
  CHECK((*log)[2].latencyMs == 800);
  CHECK((*log)[3].questionId == "q.c");
  for (const auto& e : *log) CHECK(e.rebuilt);
  CHECK(progress.reviewLog(2)->size() == 1);

  // The Leitner rows are kept as they were.
  auto kept = db->prepare("SELECT count(*) FROM leitner_progress");
  REQUIRE(*kept->step());
  CHECK(kept->int64(0) == 5);
}

TEST_CASE("A PostgreSQL database from a newer program version is refused and keeps its rows and version") {
  test::TempDir dir;
  const std::string location = test::freshDatabase(dir, "newer.db");
  if (!isPostgresUrl(location)) return;  // the SQLite file's case is the next test
  {
    auto db = Database::open(location);
    REQUIRE(db);
    REQUIRE(registerDataset(*db, sampleRecord("x"), {}));
    test::forceSchemaVersion(*db, latestSchemaVersion() + 1);
  }
  auto refused = Database::open(location);
  REQUIRE(!refused);
  CHECK(refused.error().message.find("newer version") != std::string::npos);
  CHECK(test::postgresValue(location, "SELECT version FROM at_schema_version") ==
        std::to_string(latestSchemaVersion() + 1));
  CHECK(test::postgresValue(location, "SELECT name FROM datasets") == "x");
}

TEST_CASE("A database file from a newer program version is refused and left byte-identical") {
  test::TempDir dir;
  const fs::path path = dir / "newer.db";
  {
    auto db = Database::open(path.string());
    REQUIRE(db);
    REQUIRE(registerDataset(*db, sampleRecord("x"), {}));
    // Rows in the newest tables too (review responses): a newer program's data must survive.
    REQUIRE(db->exec("INSERT INTO users (id, name) VALUES (1, 'u');"
                     "INSERT INTO review_responses (user_id, question_id, structure, answer, correct, score, latency_ms,"
                     " answered_at) VALUES (1, 'q', 's', '{\"choice\":1}', 1, 1, 10, 20)"));
    REQUIRE(db->exec("PRAGMA user_version = " + std::to_string(latestSchemaVersion() + 1)));
    // Leave the file as a rollback-journal database with no side files, so any write shows.
    REQUIRE(db->exec("PRAGMA journal_mode = DELETE"));
  }
  REQUIRE(!fs::exists(path.string() + "-wal"));
  const std::string before = readBytes(path);
  const auto mtime = fs::last_write_time(path);

  auto refused = Database::open(path.string());
  REQUIRE(!refused);
  CHECK(refused.error().message.find("newer version") != std::string::npos);
  CHECK(refused.error().message.find(path.string()) != std::string::npos);
  CHECK(readBytes(path) == before);
  CHECK(fs::last_write_time(path) == mtime);
  CHECK(!fs::exists(path.string() + "-wal"));
}

TEST_CASE("A file that is not a database is refused with its name and left untouched") {
  test::TempDir dir;
  const fs::path path = dir / "notes.db";
  {
    std::ofstream f(path, std::ios::binary);
    f << "these are my lecture notes, not a database\n" << std::string(600, 'x');
  }
  const std::string before = readBytes(path);
  auto refused = Database::open(path.string());
  REQUIRE(!refused);
  CHECK(refused.error().message.find("notes.db") != std::string::npos);
  CHECK(readBytes(path) == before);
}

TEST_CASE("openDatabase creates the folder of the default path under XDG_DATA_HOME") {
  test::TempDir dir;
  const char* old = std::getenv("XDG_DATA_HOME");
  const std::string saved = old ? old : "";
  ::setenv("XDG_DATA_HOME", (dir / "xdg").c_str(), 1);
  auto path = defaultDatabasePath();
  REQUIRE(path);
  CHECK(*path == (dir / "xdg" / "anatomy-tutor" / "anatomy-tutor.db").string());
  auto db = openDatabase(std::nullopt);
  if (old) ::setenv("XDG_DATA_HOME", saved.c_str(), 1); else ::unsetenv("XDG_DATA_HOME");
  REQUIRE(db);
  CHECK(fs::exists(*path));
}

TEST_CASE("A transaction that dies uncommitted is rolled back; a committed one persists") {
  test::TempDir dir;
  auto db = Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db);
  {
    auto tx = Transaction::begin(*db);
    REQUIRE(tx);
    REQUIRE(db->exec("INSERT INTO presets (id, mode, json) VALUES ('lost', 'wdt', '{}')"));
  }
  CHECK(countRows(*db, "presets") == 0);
  {
    auto tx = Transaction::begin(*db);
    REQUIRE(tx);
    REQUIRE(db->exec("INSERT INTO presets (id, mode, json) VALUES ('kept', 'wdt', '{}')"));
    REQUIRE(tx->commit());
  }
  CHECK(countRows(*db, "presets") == 1);
  auto failed = db->writeTransaction([](Database& d) -> Status {
    if (auto s = d.exec("INSERT INTO presets (id, mode, json) VALUES ('half', 'wdt', '{}')"); !s) return s;
    return fail("the second half failed");
  });
  CHECK(!failed);
  CHECK(countRows(*db, "presets") == 1);
}

TEST_CASE("Names and free text with quotes, semicolons and SQL keywords are stored verbatim") {
  test::TempDir dir;
  auto db = Database::open(test::freshDatabase(dir, "h.db"));
  REQUIRE(db);
  const std::vector<std::string> hostile = {
      "Robert'); DROP TABLE datasets;--",
      "\"quoted\" name; SELECT * FROM users WHERE 1=1 OR ''='",
      "O'Brien's \"ear\" -- comment /* block */",
      "naïve façade ✓ \t tab\nnewline",
      std::string("embedded\0nul", 12),
  };
  std::int64_t stored = 0;
  for (std::size_t i = 0; i < hostile.size(); ++i) {
    DatasetRecord r = sampleRecord(hostile[i]);
    r.species = hostile[(i + 1) % hostile.size()];
    r.volumePath = "/tmp/" + hostile[(i + 2) % hostile.size()];
    Structure st;
    st.label = 7;
    st.id = hostile[(i + 3) % hostile.size()];
    st.displayName = hostile[(i + 4) % hostile.size()];
    st.description = hostile[i];
    auto id = registerDataset(*db, r, {st});
    const bool nul = r.name.find('\0') != std::string::npos || r.species.find('\0') != std::string::npos ||
                     r.volumePath.find('\0') != std::string::npos || st.id.find('\0') != std::string::npos ||
                     st.displayName.find('\0') != std::string::npos || st.description.find('\0') != std::string::npos;
    if (nul && db->backend() == Backend::Postgres) {
      // PostgreSQL text cannot hold a NUL byte: refused as invalid, nothing stored.
      REQUIRE(!id);
      CHECK((id.error().kind == ErrorKind::Invalid));
      CHECK(id.error().message.find("NUL") != std::string::npos);
      continue;
    }
    REQUIRE_MESSAGE(id, (id ? "" : id.error().message));
    ++stored;
    auto back = findDataset(*db, hostile[i]);
    REQUIRE(back);
    REQUIRE(back->has_value());
    CHECK((*back)->name == r.name);
    CHECK((*back)->species == r.species);
    CHECK((*back)->volumePath == r.volumePath);
    auto structures = datasetStructures(*db, *id);
    REQUIRE(structures);
    REQUIRE(structures->size() == 1);
    CHECK((*structures)[0].id == st.id);
    CHECK((*structures)[0].displayName == st.displayName);
    CHECK((*structures)[0].description == st.description);
  }
  CHECK(countRows(*db, "datasets") == stored);
}

TEST_CASE("Registering a dataset under a name already used fails and writes nothing") {
  test::TempDir dir;
  auto db = Database::open(test::freshDatabase(dir, "d.db"));
  REQUIRE(db);
  Structure st;
  st.label = 1;
  st.id = "liver";
  st.displayName = "Liver";
  REQUIRE(registerDataset(*db, sampleRecord("abdomen"), {st}));
  auto again = registerDataset(*db, sampleRecord("abdomen"), {st});
  REQUIRE(!again);
  CHECK(again.error().message.find("'abdomen' is already imported") != std::string::npos);
  CHECK((again.error().kind == ErrorKind::Conflict));
  CHECK(countRows(*db, "datasets") == 1);
  CHECK(countRows(*db, "structures") == 1);
  auto listed = listDatasets(*db);
  REQUIRE(listed);
  REQUIRE(listed->size() == 1);
  CHECK((*listed)[0].structureCount == 1);
  CHECK((*listed)[0].species == "dog");
  CHECK((*listed)[0].geometry.dims == Dims{4, 5, 6});
}

TEST_CASE("How a dataset's values are read (unit, intercept, slope, modality) is kept with it; damaged stored options are one-line errors") {
  test::TempDir dir;
  auto db = Database::open(test::freshDatabase(dir, "d.db"));
  REQUIRE(db);
  DatasetRecord r = sampleRecord("headsq");
  r.intensity = IntensityChoice::Hounsfield;
  r.intercept = -1024;
  r.slope = 0.5;
  r.modality = "MR";
  REQUIRE(registerDataset(*db, r, {}));
  REQUIRE(registerDataset(*db, sampleRecord("plain"), {}));
  auto found = findDataset(*db, "headsq");
  REQUIRE(found);
  REQUIRE(*found);
  CHECK(((**found).intensity == IntensityChoice::Hounsfield));
  CHECK((**found).intercept == std::optional<double>(-1024));
  CHECK((**found).slope == std::optional<double>(0.5));
  const DatasetFiles files = datasetFiles(**found);
  CHECK((files.intensity == IntensityChoice::Hounsfield));
  CHECK(files.intercept == std::optional<double>(-1024));
  CHECK(files.slope == std::optional<double>(0.5));
  CHECK((**found).modality == "MR");
  CHECK(files.modality == "MR");
  CHECK(loadOptionArguments(**found) == " --intensity hu --intercept -1024 --slope 0.5 --modality MR");
  auto other = findDataset(*db, "plain");
  REQUIRE(other);
  REQUIRE(*other);
  CHECK(((**other).intensity == IntensityChoice::Auto));
  CHECK_FALSE((**other).intercept);
  CHECK_FALSE((**other).slope);
  CHECK((**other).modality.empty());
  CHECK(loadOptionArguments(**other).empty());
  // Stored options of the wrong type or value (a hand-edited or hostile database file): reading the
  // dataset fails with one line naming the option, never an exception or a silent default.
  for (const auto& [json, field] : {std::pair{R"({"intercept": "minus"})", "intercept"},
                                    std::pair{R"({"slope": 0})", "slope"},
                                    std::pair{R"({"slope": null})", "slope"},
                                    std::pair{R"({"intensity": "kelvin"})", "intensity"},
                                    std::pair{R"({"intensity": 3})", "intensity"},
                                    std::pair{R"({"skip_unreadable": "yes"})", "skip_unreadable"},
                                    std::pair{R"({"data_folder": 7})", "data_folder"},
                                    std::pair{R"({"modality": "mr"})", "modality"},
                                    std::pair{R"({"modality": "MR\n"})", "modality"},
                                    std::pair{R"({"modality": 1})", "modality"}}) {
    CAPTURE(json);
    auto update = db->prepare("UPDATE datasets SET load_options = ?1 WHERE name = 'headsq'");
    REQUIRE(update);
    update->bind(1, std::string(json));
    REQUIRE(update->run());
    auto damaged = findDataset(*db, "headsq");
    REQUIRE_FALSE(damaged);
    CHECK(damaged.error().message.find("dataset 'headsq': stored load option " + std::string(field)) != std::string::npos);
    CHECK(damaged.error().message.find('\n') == std::string::npos);
  }
}

TEST_CASE("Saving edited labels replaces the files and structures of that dataset only; an unknown name writes nothing") {
  test::TempDir dir;
  auto db = Database::open((dir / "s.db").string());
  REQUIRE(db);
  Structure liver;
  liver.label = 1;
  liver.id = "liver";
  liver.displayName = "Liver";
  REQUIRE(registerDataset(*db, sampleRecord("abdomen"), {liver}));
  auto otherId = registerDataset(*db, sampleRecord("thorax"), {liver});
  REQUIRE(otherId);

  Structure spleen = liver, kidney = liver;
  spleen.label = 3, spleen.id = "spleen", spleen.displayName = "Spleen", spleen.colour = {0.1f, 0.2f, 0.9f};
  kidney.label = 4, kidney.id = "kidney", kidney.displayName = "Kidney";
  auto saved = saveDatasetLabels(*db, "abdomen", "/data/labels/abdomen.nii.gz", "sha256:ab", "/data/labels/abdomen.json",
                                 {spleen, kidney});
  REQUIRE_MESSAGE(saved, saved.error().message);
  auto record = findDataset(*db, "abdomen");
  REQUIRE(record);
  REQUIRE(record->has_value());
  CHECK((*record)->labelsPath == "/data/labels/abdomen.nii.gz");
  CHECK((*record)->labelsChecksum == "sha256:ab");
  CHECK((*record)->namesPath == "/data/labels/abdomen.json");
  CHECK((*record)->volumePath == sampleRecord("abdomen").volumePath);  // the volume stays
  CHECK((*record)->structureCount == 2);
  auto structures = datasetStructures(*db, (*record)->id);
  REQUIRE(structures);
  REQUIRE(structures->size() == 2);
  CHECK((*structures)[0].id == "spleen");
  CHECK((*structures)[0].colour[2] == doctest::Approx(0.9));
  CHECK((*structures)[1].id == "kidney");
  auto untouched = datasetStructures(*db, *otherId);
  REQUIRE(untouched);
  REQUIRE(untouched->size() == 1);
  CHECK((*untouched)[0].id == "liver");

  auto unknown = saveDatasetLabels(*db, "pelvis", "/x.nii.gz", "sha256:00", "", {liver});
  REQUIRE(!unknown);
  CHECK((unknown.error().kind == ErrorKind::NotFound));
  CHECK(unknown.error().message.find("'pelvis'") != std::string::npos);
  CHECK(countRows(*db, "structures") == 3);
  // A structure list that breaks a constraint (the same label twice) rolls the whole save back.
  auto broken = saveDatasetLabels(*db, "abdomen", "/y.nii.gz", "sha256:cd", "", {spleen, spleen});
  CHECK(!broken);
  auto after = findDataset(*db, "abdomen");
  REQUIRE(after);
  CHECK((*after)->labelsPath == "/data/labels/abdomen.nii.gz");
  CHECK((*after)->structureCount == 2);
}

TEST_CASE("Structures keep their review states through saves; a save without states keeps the stored ones") {
  test::TempDir dir;
  auto db = Database::open((dir / "r.db").string());
  REQUIRE(db);
  Structure liver, spleen;
  liver.label = 1, liver.id = "liver", liver.displayName = "Liver";
  spleen.label = 2, spleen.id = "spleen", spleen.displayName = "Spleen";
  auto id = registerDataset(*db, sampleRecord("abdomen"), {liver, spleen});
  REQUIRE(id);
  const auto states = [&] {
    auto read = datasetReviewStates(*db, *id);
    REQUIRE_MESSAGE(read, read.error().message);
    return *read;
  };
  // Imported structures start not started.
  CHECK(states() == ReviewStates{{"liver", ReviewState::NotStarted}, {"spleen", ReviewState::NotStarted}});
  const ReviewStates set{{"liver", ReviewState::Completed}, {"spleen", ReviewState::Flagged}};
  REQUIRE(saveDatasetLabels(*db, "abdomen", "/l1.nii.gz", "sha256:01", "", {liver, spleen}, &set));
  CHECK(states() == set);
  // The `segment --save` path gives no states: each structure keeps its own; a new one starts.
  Structure kidney = liver;
  kidney.label = 3, kidney.id = "kidney", kidney.displayName = "Kidney";
  REQUIRE(saveDatasetLabels(*db, "abdomen", "/l2.nii.gz", "sha256:02", "", {liver, spleen, kidney}));
  CHECK(states() == ReviewStates{{"liver", ReviewState::Completed}, {"spleen", ReviewState::Flagged},
                                 {"kidney", ReviewState::NotStarted}});
  const ReviewStates inProgress{{"kidney", ReviewState::InProgress}};
  REQUIRE(saveDatasetLabels(*db, "abdomen", "/l3.nii.gz", "sha256:03", "", {spleen, kidney}, &inProgress));
  CHECK(states() == ReviewStates{{"spleen", ReviewState::NotStarted}, {"kidney", ReviewState::InProgress}});
  // The stored names, both ways; anything else is refused by the table.
  for (ReviewState s : kReviewStates) {
    CHECK(reviewStateNamed(reviewStateId(s)) == s);
    CHECK(reviewStateNamed(reviewStateText(s)) == s);
  }
  CHECK_FALSE(reviewStateNamed("done"));
  CHECK_FALSE(db->exec("UPDATE structures SET review_state = 'done'"));
  CHECK(states().at("kidney") == ReviewState::InProgress);
}

TEST_CASE("openExistingDatabase on a database that does not exist gives none and creates nothing") {
  test::TempDir dir;
  const fs::path path = dir / "missing" / "x.db";
  auto none = openExistingDatabase(path.string());
  REQUIRE(none);
  CHECK(!none->has_value());
  CHECK(!fs::exists(path));
  CHECK(!fs::exists(dir / "missing"));
  const fs::path present = dir / "x.db";
  REQUIRE(Database::open(present.string()));
  auto opened = openExistingDatabase(present.string());
  REQUIRE(opened);
  REQUIRE(opened->has_value());
  CHECK((*opened)->path() == present.string());
}

TEST_CASE("openDatabase with an explicit path refuses a folder that does not exist instead of creating it") {
  test::TempDir dir;
  const fs::path path = dir / "no" / "such" / "x.db";
  auto refused = openDatabase(path.string());
  REQUIRE(!refused);
  CHECK((refused.error().kind == ErrorKind::NotFound));
  CHECK(refused.error().message.find((dir / "no" / "such").string()) != std::string::npos);
  CHECK(!fs::exists(dir / "no"));
}

TEST_CASE("One connection shared by threads: concurrent write transactions lose no row and never mix") {
  test::TempDir dir;
  auto db = Database::open(test::freshDatabase(dir, "shared.db"));
  REQUIRE(db);
  constexpr int kPerThread = 100;
  std::vector<std::string> errors(3);
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t)
    threads.emplace_back([&, t] {
      for (int i = 0; i < kPerThread; ++i) {
        // Two inserts per transaction: a transaction taking in another thread's insert, or a
        // BEGIN inside another thread's transaction, would show as an error or a lost pair.
        auto st = db->writeTransaction([&](Database& d) -> Status {
          for (int half = 0; half < 2; ++half) {
            auto insert = d.prepare("INSERT INTO presets (id, mode, json) VALUES (?1, 'wdt', '{}')");
            if (!insert) return tl::unexpected(insert.error());
            insert->bind(1, "t" + std::to_string(t) + "_" + std::to_string(i) + "_" + std::to_string(half));
            if (auto s = insert->run(); !s) return s;
          }
          if (i % 7 == 3) return fail("rolled back on purpose");
          return {};
        });
        if (!st && st.error().message != "rolled back on purpose" && errors[std::size_t(t)].empty())
          errors[std::size_t(t)] = st.error().message;
      }
    });
  for (auto& th : threads) th.join();
  for (const auto& e : errors) CHECK_MESSAGE(e.empty(), e);
  int rolledBack = 0;
  for (int i = 0; i < kPerThread; ++i) rolledBack += i % 7 == 3 ? 1 : 0;
  CHECK(countRows(*db, "presets") == 3 * 2 * (kPerThread - rolledBack));
}

TEST_CASE("Several programs opening one fresh database at once create its schema once, all succeed") {
  // Lab machines starting together against a new class server: each Database::open migrates; the
  // migrations must run exactly once, and the others must see them done (not "already exists").
  test::TempDir dir;
  const std::string location = test::freshDatabase(dir, "fresh.db");
  constexpr int kPrograms = 6;
  std::vector<std::string> errors(kPrograms);
  std::latch start(kPrograms);
  std::vector<std::thread> programs;
  for (int p = 0; p < kPrograms; ++p)
    programs.emplace_back([&, p] {
      start.arrive_and_wait();
      auto db = Database::open(location);
      if (!db) errors[std::size_t(p)] = db.error().message;
    });
  for (auto& t : programs) t.join();
  for (const auto& e : errors) CHECK_MESSAGE(e.empty(), e);
  auto db = Database::open(location);
  REQUIRE(db);
  CHECK(*db->schemaVersion() == latestSchemaVersion());
}

TEST_CASE("A program opening a SQLite file while another migrates it never takes the file for another program's") {
  // A lab machine that starts a moment later than another: the file already holds some of the
  // first program's tables (its migrations commit one by one). Every state it can see must read as
  // ours: empty, or marked. Twenty rounds of one migrating program and one that keeps opening (an
  // open that gets past the inspection waits for the migration's lock, so a round may see one state).
  if (test::testingOnPostgres()) return;  // the mark and the file inspection are SQLite's
  int opensWhileMigrating = 0;
  for (int round = 0; round < 20; ++round) {
    test::TempDir dir;
    const std::string location = test::freshDatabase(dir, "fresh.db");
    std::atomic<bool> migrated{false};
    std::string migratorError;
    std::vector<std::string> errors;
    std::thread migrator([&] {
      auto db = Database::open(location);
      if (!db) migratorError = db.error().message;
      migrated = true;
    });
    // The latecomer opens at schema version 0: it reads and marks, and leaves the migrating to the
    // first program, so it keeps inspecting the file throughout the other's migrations.
    OpenOptions latecomer;
    latecomer.targetVersion = 0;
    while (!migrated) {
      std::error_code ec;
      if (!std::filesystem::exists(location, ec) || std::filesystem::file_size(location, ec) == 0) continue;
      auto db = Database::open(location, latecomer);
      if (!db) errors.push_back(db.error().message);
      ++opensWhileMigrating;
    }
    migrator.join();
    CHECK_MESSAGE(migratorError.empty(), migratorError);
    for (const auto& e : errors) CHECK_MESSAGE(e.empty(), e);
    auto db = Database::open(location);
    REQUIRE(db);
    CHECK(*db->schemaVersion() == latestSchemaVersion());
  }
  MESSAGE(opensWhileMigrating << " opens while the other program migrated");
  CHECK(opensWhileMigrating > 0);
}

TEST_CASE("A class server that closes the connection or restarts: the program goes on, nothing lost or doubled") {
  if (!test::testingOnPostgres()) return;  // a server's behaviour
  test::PrivatePostgres server;             // stopped below: a cluster of its own, not the shared one
  const auto fresh = server.freshDatabase("the server-restart test");
  if (!fresh) return;
  const std::string url = *fresh;
  auto db = Database::open(url);
  REQUIRE(db);
  const auto insertPreset = [&](const std::string& id) {
    return db->writeTransaction([&](Database& d) -> Status {
      auto insert = d.prepare("INSERT INTO presets (id, mode, json) VALUES (?1, 'wdt', '{}')");
      if (!insert) return tl::unexpected(insert.error());
      insert->bind(1, id);
      return insert->run();
    });
  };
  REQUIRE(insertPreset("before"));
  // The server ends this program's session while it is idle (an administrator, an idle timeout).
  auto pid = db->prepare("SELECT pg_backend_pid()");
  REQUIRE(pid);
  REQUIRE(*pid->step());
  REQUIRE(test::postgresValue(url, "SELECT pg_terminate_backend(" + std::to_string(pid->int64(0)) + ")") == "t");
  CHECK(insertPreset("after terminate"));
  CHECK(countRows(*db, "presets") == 2);

  REQUIRE(server.stop());
  auto whileDown = insertPreset("while down");
  bool restarted = server.restart();
  REQUIRE(restarted);
  REQUIRE_FALSE(whileDown);
  CHECK((whileDown.error().kind == ErrorKind::Unavailable));
  CHECK(whileDown.error().message.find("database server") != std::string::npos);
  CHECK(whileDown.error().message.find('\n') == std::string::npos);
  CHECK(insertPreset("after restart"));
  auto ids = db->prepare("SELECT id FROM presets ORDER BY id");
  REQUIRE(ids);
  std::vector<std::string> stored;
  while (*ids->step()) stored.push_back(ids->text(0));
  CHECK(stored == std::vector<std::string>{"after restart", "after terminate", "before"});
}

TEST_CASE("Two connections writing at once through writeTransaction lose no row") {
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "c.db");
  REQUIRE(Database::open(path));
  constexpr int kPerWriter = 150;
  auto writer = [&](int w, std::string* error) {
    auto db = Database::open(path);
    if (!db) {
      *error = db.error().message;
      return;
    }
    for (int i = 0; i < kPerWriter; ++i) {
      auto s = db->writeTransaction([&](Database& d) -> Status {
        auto insert = d.prepare("INSERT INTO presets (id, mode, json) VALUES (?1, 'wdt', '{}')");
        if (!insert) return tl::unexpected(insert.error());
        insert->bind(1, "w" + std::to_string(w) + "-" + std::to_string(i));
        return insert->run();
      });
      if (!s) {
        *error = s.error().message;
        return;
      }
    }
  };
  std::string e1, e2;
  std::thread a(writer, 1, &e1), b(writer, 2, &e2);
  a.join();
  b.join();
  CHECK(e1.empty());
  CHECK(e2.empty());
  auto db = Database::open(path);
  REQUIRE(db);
  CHECK(countRows(*db, "presets") == 2 * kPerWriter);
}

TEST_CASE("SHA-256 matches the FIPS 180-4 test vectors") {
  CHECK(sha256Hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(sha256Hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  CHECK(sha256Hex(std::string(1000000, 'a')) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST_CASE("checksumPath hashes a file's bytes and notices a changed file in a folder") {
  test::TempDir dir;
  fs::create_directories(dir / "series");
  { std::ofstream(dir / "series" / "1.dcm", std::ios::binary) << "slice one"; }
  { std::ofstream(dir / "series" / "2.dcm", std::ios::binary) << "slice two"; }
  auto file = checksumPath((dir / "series" / "1.dcm").string());
  REQUIRE(file);
  CHECK(*file == "sha256:" + sha256Hex("slice one"));
  auto folder = checksumPath((dir / "series").string());
  REQUIRE(folder);
  { std::ofstream(dir / "series" / "2.dcm", std::ios::binary) << "slice 2!!"; }
  auto changed = checksumPath((dir / "series").string());
  REQUIRE(changed);
  CHECK(*changed != *folder);
  CHECK(!checksumPath((dir / "nothing").string()));
}

// A detached NRRD header (headsq's: 93 slice files) names its data in other files: the checksum a
// dataset records covers each of them, so a slice file changed after an import is noticed, not only
// a changed header. The header's bytes alone (what was recorded before) stay readable for datasets
// imported then.
TEST_CASE("checksumPath of a detached NRRD header covers every data file it names, each file's change noticed") {
  test::TempDir dir;
  const int slices = 5;
  {
    std::ofstream header(dir / "h.nhdr", std::ios::binary);
    header << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 " << slices
           << "\nencoding: raw\ndata file: s%d.raw 1 " << slices << " 1\n";
  }
  for (int n = 1; n <= slices; ++n) std::ofstream(dir / ("s" + std::to_string(n) + ".raw"), std::ios::binary) << std::string(12, char('a' + n));
  const std::string header = (dir / "h.nhdr").string();
  auto first = checksumPath(header);
  REQUIRE_MESSAGE(first, first.error().message);
  auto headerOnly = headerOnlyNrrdChecksum(header);
  REQUIRE(headerOnly);
  REQUIRE(*headerOnly);
  CHECK(**headerOnly == "sha256:" + sha256Hex(test::readFile(dir / "h.nhdr")));
  CHECK(*first != **headerOnly);
  std::set<std::string> seen{*first};
  for (int n = 1; n <= slices; ++n) {
    CAPTURE(n);
    const fs::path slice = dir / ("s" + std::to_string(n) + ".raw");
    const std::string before = test::readFile(slice);
    std::string changed = before;
    changed[std::size_t(n) % changed.size()] ^= 1;  // one bit of one slice
    { std::ofstream(slice, std::ios::binary) << changed; }
    auto now = checksumPath(header);
    REQUIRE(now);
    CHECK(seen.insert(*now).second);  // differs from the original and from every other change
    CHECK(**headerOnlyNrrdChecksum(header) == **headerOnly);
    { std::ofstream(slice, std::ios::binary) << before; }
  }
  CHECK(*checksumPath(header) == *first);
  // A missing slice is an error naming it; a header whose data lie outside its folder is refused
  // as the loader refuses it, unless that folder is the one allowed.
  fs::rename(dir / "s3.raw", dir / "s3.moved");
  auto missing = checksumPath(header);
  REQUIRE_FALSE(missing);
  CHECK(missing.error().message.find("s3.raw") != std::string::npos);
  fs::rename(dir / "s3.moved", dir / "s3.raw");
  fs::create_directories(dir / "h");
  { std::ofstream(dir / "h" / "out.nhdr", std::ios::binary) << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 1\nencoding: raw\ndata file: ../s1.raw\n"; }
  auto outside = checksumPath((dir / "h" / "out.nhdr").string());
  REQUIRE_FALSE(outside);
  CHECK(outside.error().message.find("lies outside") != std::string::npos);
  CHECK(checksumPath((dir / "h" / "out.nhdr").string(), dir.path().string()));
  // A file named again (LIST may name one file up to a million times) is hashed once and stands
  // as its first naming afterwards: a header naming s1 then s1 differs from one naming s1 then a
  // copy of it, and a change to s1 still shows.
  { std::ofstream(dir / "s1copy.raw", std::ios::binary) << test::readFile(dir / "s1.raw"); }
  const auto listHeader = [&](const std::string& name, const std::string& second) {
    std::ofstream(dir / name, std::ios::binary) << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 2\nencoding: raw\ndata file: LIST\ns1.raw\n"
                                                  << second << "\n";
    return (dir / name).string();
  };
  const std::string twice = listHeader("twice.nhdr", "s1.raw"), copied = listHeader("copied.nhdr", "s1copy.raw");
  auto twiceSum = checksumPath(twice);
  REQUIRE_MESSAGE(twiceSum, twiceSum.error().message);
  CHECK(*twiceSum != *checksumPath(copied));
  { std::ofstream(dir / "s1.raw", std::ios::binary) << std::string(12, 'z'); }
  CHECK(*checksumPath(twice) != *twiceSum);
  // An attached NRRD and any other file: the file's bytes, as before.
  { std::ofstream(dir / "a.nrrd", std::ios::binary) << "NRRD0004\ntype: uint8\ndimension: 1\nsizes: 2\nencoding: raw\n\nab"; }
  CHECK(*checksumPath((dir / "a.nrrd").string()) == "sha256:" + sha256Hex(test::readFile(dir / "a.nrrd")));
  auto attached = headerOnlyNrrdChecksum((dir / "a.nrrd").string());
  REQUIRE(attached);
  CHECK(!*attached);
}

TEST_CASE("SqlErrors_CarryTheirKind_UniqueIsConflict_MissingReferenceIsNotFound_CheckIsInvalid") {
  test::TempDir dir;
  auto db = Database::open(test::freshDatabase(dir, "k.db"));
  REQUIRE(db);
  REQUIRE(db->exec("INSERT INTO presets (id, mode, json) VALUES ('p', 'wdt', '{}')"));
  auto clash = db->exec("INSERT INTO presets (id, mode, json) VALUES ('p', 'bare', '{}')");
  REQUIRE(!clash);
  CHECK((clash.error().kind == ErrorKind::Conflict));
  auto orphan = db->exec("INSERT INTO attempts (user_id, lesson_id, mode, started_at) VALUES (424242, 'l', 'guided', 1)");
  REQUIRE(!orphan);
  CHECK((orphan.error().kind == ErrorKind::NotFound));
  REQUIRE(db->exec("INSERT INTO users (name, role) VALUES ('u', 'student')"));
  auto badMode = db->exec("INSERT INTO attempts (user_id, lesson_id, mode, started_at) VALUES (1, 'l', 'exam!', 1)");
  REQUIRE(!badMode);
  CHECK((badMode.error().kind == ErrorKind::Invalid));
}

TEST_CASE("A structure's system is stored for that structure of that dataset only; unknown names write nothing") {
  test::TempDir dir;
  auto db = Database::open((dir / "s.db").string());
  REQUIRE(db);
  Structure liver, spleen;
  liver.label = 1, liver.id = "liver", liver.displayName = "Liver";
  spleen.label = 2, spleen.id = "spleen", spleen.displayName = "Spleen", spleen.system = "lymphatic";
  auto id = registerDataset(*db, sampleRecord("abdomen"), {liver, spleen});
  auto otherId = registerDataset(*db, sampleRecord("thorax"), {liver});
  REQUIRE(id);
  REQUIRE(otherId);
  REQUIRE(setStructureSystem(*db, "abdomen", "liver", "digestive"));
  auto structures = datasetStructures(*db, *id);
  REQUIRE(structures);
  REQUIRE(structures->size() == 2);
  CHECK((*structures)[0].system == "digestive");
  CHECK((*structures)[1].system == "lymphatic");
  auto other = datasetStructures(*db, *otherId);
  REQUIRE(other);
  CHECK((*other)[0].system.empty());
  for (auto [dataset, structure, named] : {std::tuple{"pelvis", "liver", "'pelvis'"}, {"abdomen", "heart", "'heart'"}}) {
    auto refused = setStructureSystem(*db, dataset, structure, "x");
    REQUIRE(!refused);
    CHECK((refused.error().kind == ErrorKind::NotFound));
    CHECK(refused.error().message.find(named) != std::string::npos);
  }
  auto again = datasetStructures(*db, *id);
  REQUIRE(again);
  CHECK((*again)[0].system == "digestive");
  REQUIRE(setStructureSystem(*db, "abdomen", "liver", ""));  // cleared
  CHECK((*datasetStructures(*db, *id))[0].system.empty());
}
