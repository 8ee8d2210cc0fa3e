// The staging folder of a course package import, and what is left of one after a crash.
//
// An import extracts into <data folder>/staging-XXXXXX/dataset/, checks everything there, writes
// the folder it is meant for (datasets/<name>) into staging-XXXXXX/target, commits the database
// rows in one transaction, and only then renames staging-XXXXXX/dataset to datasets/<name>. The
// importing process holds an advisory lock (flock) on its staging folder for its whole life.
//
// recoverStaging, run before every import and when a learning session opens, looks at each
// unlocked staging-* folder (its process is gone): when the database holds the dataset its
// `target` names, with the checksum of the staged volume, and the target folder is missing, the
// interrupted import is completed (the rename); otherwise the folder is removed. So a kill at any
// point leaves the old state or the new one.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/regular_file.h"
#include "db/connection.h"

namespace at::app {

class ImportStaging {
 public:
  // A fresh, locked staging folder in `dataFolder` (created when missing).
  static Result<ImportStaging> make(const std::filesystem::path& dataFolder);
  ImportStaging(ImportStaging&& other) noexcept
      : folder_(std::move(other.folder_)), lock_(std::move(other.lock_)), createdParent_(other.createdParent_) {
    other.folder_.clear();
  }
  ImportStaging& operator=(ImportStaging&&) = delete;
  ImportStaging(const ImportStaging&) = delete;
  // Removes the folder unless it was committed, and the data folder too when make created it and
  // it is empty again (a refused import leaves the user's folders as they were).
  ~ImportStaging();

  const std::filesystem::path& folder() const { return folder_; }
  // Where the package's files are extracted (created by make).
  std::filesystem::path datasetFolder() const { return folder_ / "dataset"; }
  // Records (and flushes to disk) which dataset folder the staged files are for, before the
  // database commit.
  Status recordTarget(const std::string& datasetName);
  // After the commit: moves the staged files to `target` and removes the staging folder.
  Status moveInto(const std::filesystem::path& target);

 private:
  ImportStaging(std::filesystem::path folder, FileDescriptor lock) : folder_(std::move(folder)), lock_(std::move(lock)) {}
  std::filesystem::path folder_;
  FileDescriptor lock_;  // the folder itself, flock'ed
  bool createdParent_ = false;
};

// What recoverStaging did with each leftover folder (for logs and tests).
struct StagingRecovery {
  std::vector<std::string> completed;  // dataset names whose interrupted import was finished
  std::size_t removed = 0;             // staging folders removed
};

// Finishes or removes the staging folders no running process holds (see above). `dataFolder`
// may not exist (nothing to do).
Result<StagingRecovery> recoverStaging(db::Database& database, const std::filesystem::path& dataFolder);

// A test hook for kill-during-import tests: when AT_TEST_IMPORT_KILL_AT names `point`, the
// process kills itself there with SIGKILL (as a crash or a power cut would stop it).
void importCrashPoint(const char* point);

}  // namespace at::app
