// Broken and hostile databases: a file the program did not write as it is — a schema
// version outside 0..current, a damaged page — is refused before anything writes to it; two runs
// for one study participant cannot interleave; imported files changed since their import are
// refused by checksum.
#include <doctest/doctest.h>

#include <climits>
#include <filesystem>
#include <fstream>
#include <string>

#include "db/checksum.h"
#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/dataset_store.h"
#include "schema.h"
#include "db/study_store.h"
#include "test_support.h"

using namespace at;
using namespace at::db;
namespace fs = std::filesystem;

namespace {

std::string fileChecksum(const fs::path& path) { return sha256Hex(test::readFile(path)); }

// A database at the newest schema, closed, with `sql` run on it afterwards.
void makeDatabase(const fs::path& path, const std::string& sql = "") {
  auto db = Database::open(path.string());
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  if (!sql.empty()) REQUIRE(db->exec(sql));
}

quiz::StudyProtocol smallStudy() {
  quiz::StudyProtocol p;
  p.id = "s";
  p.dataset = "phantom";
  p.structures = {"cochlea", "stapes"};
  p.conditions = {{"wdt", "WDT", "_wdt"}, {"bare", "bare", "_bare"}};
  p.items = {{"shape", "Shape?"}};
  p.groups = {"g"};
  return p;
}

}  // namespace

TEST_CASE("A schema version outside 0..current is refused and the file left untouched") {
  // user_version −1 once made migrate index its list with −1 (a heap read out of bounds, garbage
  // SQL, a garbage version written back); INT_MIN crashed.
  test::TempDir dir;
  for (const long long version : {-1LL, -2LL, (long long)INT_MIN, (long long)latestSchemaVersion() + 1}) {
    CAPTURE(version);
    const fs::path path = dir / ("v" + std::to_string(version) + ".db");
    makeDatabase(path, "PRAGMA user_version = " + std::to_string(version));
    const std::string before = fileChecksum(path);
    auto db = Database::open(path.string());
    REQUIRE_FALSE(db);
    const std::string& message = db.error().message;
    CHECK(message.rfind(path.string() + ": ", 0) == 0);
    if (version < 0) {
      CHECK(message.find("schema version " + std::to_string(version) + " is not one any Anatomy Tutor writes") !=
            std::string::npos);
      CHECK(message.find("left untouched") != std::string::npos);
    } else {
      CHECK(message.find("written by a newer version of Anatomy Tutor") != std::string::npos);
    }
    CHECK(fileChecksum(path) == before);
    // Nothing waits in a write-ahead log either (a reader may leave an empty one beside the file).
    const fs::path wal = path.string() + "-wal";
    CHECK((!fs::exists(wal) || fs::file_size(wal) == 0));
  }
}

TEST_CASE("A damaged database is refused on open (PRAGMA quick_check) and left untouched") {
  test::TempDir dir;
  const fs::path path = dir / "damaged.db";
  makeDatabase(path);
  // Overwrite the last page (a b-tree page of some table or index) with garbage; page 1, which
  // holds the schema version, stays readable.
  std::string bytes = test::readFile(path);
  const std::size_t pageSize = (std::size_t(static_cast<unsigned char>(bytes[16])) << 8) | static_cast<unsigned char>(bytes[17]);
  REQUIRE(bytes.size() >= 4 * pageSize);
  for (std::size_t i = bytes.size() - pageSize; i < bytes.size(); ++i) bytes[i] = char(0xA5);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << bytes;
  }
  const std::string before = fileChecksum(path);
  auto db = Database::open(path.string());
  REQUIRE_FALSE(db);
  CAPTURE(db.error().message);
  CHECK(db.error().message.rfind(path.string() + ": the database is damaged (", 0) == 0);
  CHECK(db.error().message.find("it was left untouched — restore a backup or use another --db") != std::string::npos);
  CHECK((db.error().kind == ErrorKind::Io));
  CHECK(fileChecksum(path) == before);
}

TEST_CASE("Study ratings: once another session resumes a participant, the earlier session may not write") {
  // Four `study run` processes for one participant each printed success while the database kept
  // whichever rating came last; now each write checks it comes from the participant's latest session.
  test::TempDir dir;
  auto db = Database::open((dir / "s.db").string());
  REQUIRE(db);
  const auto protocol = smallStudy();
  REQUIRE(saveStudy(*db, protocol));
  auto first = enrolOrResume(*db, protocol, "P01", "g");
  REQUIRE(first);
  RatingRecord rating;
  rating.position = 0;
  rating.item = "shape";
  rating.ratingAsShown = 2;
  REQUIRE(recordRating(*db, *first, rating));

  auto second = enrolOrResume(*db, protocol, "P01", "g");
  REQUIRE(second);
  CHECK(second->session == first->session + 1);
  rating.ratingAsShown = 5;
  auto refused = recordRating(*db, *first, rating);
  REQUIRE_FALSE(refused);
  CHECK((refused.error().kind == ErrorKind::Conflict));
  CHECK(refused.error().message ==
        "study 's': participant 'P01' was resumed by another session (session 2) after this one (session 1) began; "
        "this session stops here and keeps what it saved — finish in session 2, or resume the participant again to "
        "take over");
  CHECK_FALSE(recordTrialViewing(*db, *first, 0, 1, 1, 0, ""));
  CHECK_FALSE(markParticipantComplete(*db, *first));

  rating.ratingAsShown = 4;
  REQUIRE(recordRating(*db, *second, rating));
  auto rows = studyResponseRows(*db, protocol);
  REQUIRE(rows);
  REQUIRE(rows->size() == 1);
  CHECK((*rows)[0].ratingAb == 4);
}

TEST_CASE("Imported files changed since their import are refused by checksum, and --replace registers them again") {
  test::TempDir dir;
  auto db = Database::open((dir / "d.db").string());
  REQUIRE(db);
  const fs::path volume = dir / "ct.nii", labels = dir / "labels.nii";
  {
    std::ofstream(volume) << "volume bytes";
    std::ofstream(labels) << "label bytes";
  }
  DatasetRecord record;
  record.name = "abdomen";
  record.volumePath = volume.string();
  record.labelsPath = labels.string();
  record.volumeChecksum = *checksumPath(volume.string());
  record.labelsChecksum = *checksumPath(labels.string());
  record.geometry.dims = {1, 1, 1};
  record.orientation = "LPS";
  REQUIRE(registerDataset(*db, record, {}));
  auto stored = findDataset(*db, "abdomen");
  REQUIRE(stored);
  REQUIRE(stored->has_value());
  CHECK(verifiedDatasetFiles(**stored));

  std::ofstream(labels) << "other label bytes on the same grid";
  auto changed = verifiedDatasetFiles(**stored);
  REQUIRE_FALSE(changed);
  CHECK((changed.error().kind == ErrorKind::Conflict));
  CHECK(changed.error().message.rfind("dataset 'abdomen': its labels " + labels.string() + " has changed since it was imported", 0) == 0);
  CHECK(changed.error().message.find("register it again: anatomy-tutor import --volume " + volume.string() + " --labels " +
                                     labels.string() + " --name abdomen --replace") != std::string::npos);

  CHECK_FALSE(registerDataset(*db, record, {}));  // the name is taken
  record.labelsChecksum = *checksumPath(labels.string());
  REQUIRE(registerDataset(*db, record, {}, true));
  stored = findDataset(*db, "abdomen");
  REQUIRE(stored);
  CHECK(verifiedDatasetFiles(**stored));
  auto all = listDatasets(*db);
  REQUIRE(all);
  CHECK(all->size() == 1);
}

// A detached NRRD volume: a slice file changed after the import is refused like a changed header.
// A dataset imported when the checksum covered the header alone (its record holds the header's
// checksum) still opens while its header is unchanged; a changed header is refused either way.
TEST_CASE("An imported detached NRRD's data files are checked too; a record of its header alone still opens") {
  test::TempDir dir;
  auto db = Database::open((dir / "d.db").string());
  REQUIRE(db);
  const fs::path header = dir / "ct.nhdr";
  { std::ofstream(header, std::ios::binary) << "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 2\nencoding: raw\ndata file: z%d.raw 0 1 1\n"; }
  for (const char* slice : {"z0.raw", "z1.raw"}) std::ofstream(dir / slice, std::ios::binary) << "abcd";
  DatasetRecord record;
  record.name = "slices";
  record.volumePath = header.string();
  record.volumeChecksum = *checksumPath(header.string());
  record.geometry.dims = {2, 2, 2};
  record.orientation = "LPS";
  REQUIRE(registerDataset(*db, record, {}));
  DatasetRecord legacy = record;
  legacy.name = "slices_before";
  legacy.volumeChecksum = **headerOnlyNrrdChecksum(header.string());
  REQUIRE(registerDataset(*db, legacy, {}));
  const auto verified = [&](const std::string& name) {
    auto stored = findDataset(*db, name);
    REQUIRE(stored);
    REQUIRE(stored->has_value());
    return verifiedDatasetFiles(**stored);
  };
  CHECK(verified("slices"));
  CHECK(verified("slices_before"));

  std::ofstream(dir / "z1.raw", std::ios::binary) << "abce";  // one byte of the second slice
  auto changed = verified("slices");
  REQUIRE_FALSE(changed);
  CHECK((changed.error().kind == ErrorKind::Conflict));
  CHECK(changed.error().message.rfind("dataset 'slices': its volume " + header.string() + " has changed since it was imported", 0) == 0);
  CHECK(verified("slices_before"));  // its record cannot tell: the header is as it was

  std::ofstream(dir / "z1.raw", std::ios::binary) << "abcd";
  CHECK(verified("slices"));
  { std::ofstream(header, std::ios::binary | std::ios::app) << "# a comment\n"; }
  CHECK_FALSE(verified("slices"));
  CHECK_FALSE(verified("slices_before"));
}
