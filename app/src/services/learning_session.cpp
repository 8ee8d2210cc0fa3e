#include "learning_session.h"

#include "course_packages.h"
#include "import_staging.h"

#include <cstdio>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>

#include "core/printable_text.h"
#include "core/strings.h"
#include "data_paths.h"
#include "dataset_resolver.h"
#include "db/course_store.h"
#include "db/sql_repositories.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"
#include "volume/phantom.h"
#include "wdt/answer_keys.h"

namespace at::app {

namespace {

// A KeyComputer that answers hasStructure from a structure list and loads the dataset (and
// computes distance fields) only when a key needs it: lessons without relation, order or computed
// identify questions start without building a volume.
class LazyKeyComputer final : public quiz::KeyComputer {
 public:
  using Loader = std::function<Result<Dataset>()>;
  LazyKeyComputer(std::vector<Structure> structures, Loader loader)
      : structures_(std::move(structures)), loader_(std::move(loader)) {}

  bool hasStructure(const std::string& structureId) const override {
    for (const Structure& s : structures_)
      if (s.id == structureId) return true;
    return false;
  }
  Result<quiz::StructureDistances> distancesFrom(const std::string& structureId) override {
    auto keys = loaded();
    if (!keys) return tl::unexpected(keys.error());
    return (*keys)->distancesFrom(structureId);
  }
  Result<Vec3> centroidMm(const std::string& structureId) override {
    auto keys = loaded();
    if (!keys) return tl::unexpected(keys.error());
    return (*keys)->centroidMm(structureId);
  }
  Result<std::vector<std::string>> structuresAlong(const Vec3& entryMm, const Vec3& targetMm) override {
    auto keys = loaded();
    if (!keys) return tl::unexpected(keys.error());
    return (*keys)->structuresAlong(entryMm, targetMm);
  }

 private:
  Result<quiz::KeyComputer*> loaded() {
    if (!keys_) {
      auto dataset = loader_();
      if (!dataset) return tl::unexpected(dataset.error());
      dataset_ = std::make_unique<Dataset>(std::move(*dataset));
      const Dataset& d = *dataset_;
      keys_ = std::make_unique<quiz::DatasetKeyComputer>(
          d, [&d](const Mask& seeds) { return wdt::answerKeyDistances(d.volume, d.labels.geometry, seeds); });
    }
    return keys_.get();
  }
  std::vector<Structure> structures_;
  Loader loader_;
  std::unique_ptr<Dataset> dataset_;
  std::unique_ptr<quiz::DatasetKeyComputer> keys_;
};

// A known scan's structures (skull): those of the labels scripts/label-scans.sh grew, read once
// per process (the scan and its labels are loaded for it).
Result<std::vector<Structure>> knownScanStructures(const std::string& datasetId) {
  static std::mutex mutex;
  static std::map<std::string, std::vector<Structure>> cache;
  std::lock_guard lock(mutex);
  if (auto it = cache.find(datasetId); it != cache.end()) return it->second;
  DatasetRequest request;
  request.name = datasetId;
  auto dataset = openNamedDataset(request);
  if (!dataset) return tl::unexpected(withContext("dataset '" + datasetId + "'", dataset.error()));
  if (dataset->structures.empty())
    return fail(ErrorKind::NotFound, "dataset '" + datasetId + "' has no labels yet: run `bash scripts/label-scans.sh` "
                "(it grows them with `anatomy-tutor segment` from the seeds in data/segmentations/" + datasetId + "/)");
  return cache.emplace(datasetId, std::move(dataset->structures)).first->second;
}

// The built-in datasets' structures without building their volumes ("phantom", "phantom:N"), and
// the known scans' when they can be opened with their labels.
db::BuiltinStructures builtinStructures() {
  return [](const std::string& datasetId) -> std::optional<std::vector<Structure>> {
    if (isBuiltinDatasetName(datasetId)) return phantomStructures();
    if (findKnownScan(datasetId))
      if (auto structures = knownScanStructures(datasetId)) return std::move(*structures);
    return std::nullopt;
  };
}

}  // namespace

std::string courseDirectory() { return dataSubdirectory("courses").string(); }

struct LearningSession::Repositories {
  db::SqlCurriculumRepository curriculum;
  db::SqlProgressRepository progress;
  db::SqlUserRepository users;
  explicit Repositories(db::Database& database)
      : curriculum(database, builtinStructures()), progress(database), users(database) {}
};

LearningSession::LearningSession(db::Connection connection)
    : connection_(std::move(connection)), repositories_(std::make_unique<Repositories>(connection_)) {}

LearningSession::~LearningSession() {
  // Damaged stored rows were left out rather than failing the command: say which, once each.
  if (repositories_)
    for (const std::string& line : repositories_->curriculum.takeSkipped())
      std::fprintf(stderr, "anatomy-tutor: warning: %s\n", printableText(line, 2000).c_str());
}

Result<std::unique_ptr<LearningSession>> LearningSession::open(const std::optional<std::string>& dbPath,
                                                               bool readOnly) {
  const std::string courses = courseDirectory();
  std::error_code ec;
  if (!std::filesystem::is_directory(courses, ec))
    return fail(ErrorKind::NotFound, "no course folder at " + courses + " (the courses are installed in "
                "share/anatomy-tutor/courses beside the program's bin/ folder; AT_DATA_DIR=DIR reads DIR/courses instead)");
  db::OpenOptions options;
  options.readOnlyIfNotWritable = readOnly;
  auto database = db::openDatabase(dbPath, options);
  if (!database) return tl::unexpected(database.error());
  if (database->readOnly()) return std::unique_ptr<LearningSession>(new LearningSession(std::move(*database)));
  auto seeded = db::seedCourses(*database, courses);
  if (!seeded) return tl::unexpected(withContext("seeding the default course", seeded.error()));
  // A course import killed midway is finished or cleaned up at the next start (import_staging.h);
  // a failure here leaves the folders for the next import and does not stop the session.
  if (auto assets = courseAssetDirectory(*database)) (void)recoverStaging(*database, *assets);
  return std::unique_ptr<LearningSession>(new LearningSession(std::move(*database)));
}

lessons::CurriculumRepository& LearningSession::curriculum() { return repositories_->curriculum; }
lessons::ProgressRepository& LearningSession::progress() { return repositories_->progress; }
lessons::UserRepository& LearningSession::users() { return repositories_->users; }

Result<lessons::User> LearningSession::user(const std::string& name, NewUser newUser, const std::string& group,
                                            bool* created) {
  if (created) *created = false;
  auto found = users().findUser(name);
  if (!found) return tl::unexpected(found.error());
  if (*found) return **found;
  if (newUser == NewUser::Refuse)
    return fail(ErrorKind::NotFound, "unknown user '" + name + "' (first time? add --new-user to create it)");
  auto made = users().createUser(name, lessons::Role::Student, group);
  if (!made && made.error().kind == ErrorKind::Conflict) {  // another process created it meanwhile
    auto again = users().findUser(name);
    if (again && *again) return **again;
  }
  if (!made) return tl::unexpected(withContext("user '" + name + "'", made.error()));
  if (created) *created = true;
  return *made;
}

Result<std::vector<Structure>> LearningSession::structures(const std::string& datasetId) {
  if (findKnownScan(datasetId)) return knownScanStructures(datasetId);
  return curriculum().structures(datasetId);
}

Result<quiz::KeyComputer*> LearningSession::keysFor(const std::string& datasetId) {
  if (auto it = keys_.find(datasetId); it != keys_.end()) return it->second.get();
  auto list = structures(datasetId);
  if (!list) return tl::unexpected(list.error());
  db::Database* database = &connection_.get();
  auto keys = std::make_unique<LazyKeyComputer>(std::move(*list), [database, datasetId]() -> Result<Dataset> {
    DatasetRequest request;
    request.name = datasetId;
    request.database = database;
    auto dataset = openNamedDataset(request);
    if (!dataset) return tl::unexpected(withContext("dataset '" + datasetId + "'", dataset.error()));
    return dataset;
  });
  return keys_.emplace(datasetId, std::move(keys)).first->second.get();
}

Result<std::unique_ptr<lessons::LessonEngine>> LearningSession::engineFor(const std::string& lessonId) {
  auto lesson = curriculum().lesson(lessonId);
  if (!lesson) return tl::unexpected(lesson.error());
  auto course = curriculum().course(lesson->courseId);
  if (!course) return tl::unexpected(course.error());
  auto keys = keysFor(course->datasetId);
  if (!keys) return tl::unexpected(keys.error());
  return std::make_unique<lessons::LessonEngine>(curriculum(), progress(), **keys);
}

std::map<std::string, std::string> structureIdsByName(const std::vector<Structure>& structures) {
  std::map<std::string, std::string> ids;
  for (const Structure& s : structures) {
    ids[str::lower(s.id)] = s.id;
    ids[str::lower(s.displayName)] = s.id;
  }
  return ids;
}

}  // namespace at::app
