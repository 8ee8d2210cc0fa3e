#include "import_staging.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <fstream>

#include "core/safe_name.h"
#include "db/checksum.h"
#include "db/dataset_store.h"

namespace at::app {

namespace fs = std::filesystem;

namespace {

constexpr const char* kPrefix = "staging-";
constexpr const char* kTargetFile = "target";

// The folder opened and locked exclusively; nullopt when another process holds it.
std::optional<FileDescriptor> lockFolder(const fs::path& folder, bool wait) {
  FileDescriptor fd(::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC | O_NOFOLLOW));
  if (fd.get() < 0) return std::nullopt;
  if (::flock(fd.get(), LOCK_EX | (wait ? 0 : LOCK_NB)) != 0) return std::nullopt;
  return fd;
}

Status syncPath(const fs::path& path, int flags) {
  FileDescriptor fd(::open(path.c_str(), flags | O_CLOEXEC));
  if (fd.get() < 0 || ::fsync(fd.get()) != 0) return fail(ErrorKind::Io, path.string() + ": cannot flush to disk (" + std::strerror(errno) + ")");
  return {};
}

}  // namespace

Result<ImportStaging> ImportStaging::make(const fs::path& dataFolder) {
  std::error_code ec;
  const bool created = !fs::exists(dataFolder, ec);
  fs::create_directories(dataFolder, ec);
  std::string pattern = (dataFolder / (std::string(kPrefix) + "XXXXXX")).string();
  if (ec || !::mkdtemp(pattern.data()))
    return fail(ErrorKind::Io, dataFolder.string() + ": cannot create a staging folder (" + std::strerror(errno) + ")");
  auto lock = lockFolder(pattern, true);
  if (!lock) {
    fs::remove_all(pattern, ec);
    return fail(ErrorKind::Io, pattern + ": cannot lock the staging folder");
  }
  ImportStaging staging(pattern, std::move(*lock));
  staging.createdParent_ = created;
  fs::create_directory(staging.datasetFolder(), ec);
  if (ec) return fail(ErrorKind::Io, staging.datasetFolder().string() + ": cannot create (" + ec.message() + ")");
  return Result<ImportStaging>(std::move(staging));
}

ImportStaging::~ImportStaging() {
  std::error_code ec;
  if (folder_.empty()) return;
  fs::remove_all(folder_, ec);
  if (createdParent_) fs::remove(folder_.parent_path(), ec);  // only when empty
}

Status ImportStaging::recordTarget(const std::string& datasetName) {
  const fs::path file = folder_ / kTargetFile;
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out << datasetName;
    out.close();
    if (!out) return fail(ErrorKind::Io, file.string() + ": writing failed (disk full?)");
  }
  // The staged files and the note reach the disk before the database says they exist.
  for (const auto& entry : fs::directory_iterator(datasetFolder()))
    if (entry.is_regular_file())
      if (auto ok = syncPath(entry.path(), O_RDONLY); !ok) return ok;
  if (auto ok = syncPath(file, O_RDONLY); !ok) return ok;
  if (auto ok = syncPath(datasetFolder(), O_RDONLY | O_DIRECTORY); !ok) return ok;
  return syncPath(folder_, O_RDONLY | O_DIRECTORY);
}

Status ImportStaging::moveInto(const fs::path& target) {
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  // On failure the staging folder is kept for recoverStaging (the database already names target).
  const auto keep = [&](Error error) {
    folder_.clear();
    return tl::unexpected(std::move(error));
  };
  if (fs::exists(target, ec)) return keep({ErrorKind::Conflict, target.string() + ": exists already; the staged files stay in " + folder_.string()});
  fs::rename(datasetFolder(), target, ec);
  if (ec) return keep({ErrorKind::Io, target.string() + ": cannot move the imported files into place (" + ec.message() + ")"});
  (void)syncPath(target.parent_path(), O_RDONLY | O_DIRECTORY);
  fs::remove_all(folder_, ec);
  folder_.clear();
  return {};
}

Result<StagingRecovery> recoverStaging(db::Database& database, const fs::path& dataFolder) {
  StagingRecovery report;
  std::error_code ec;
  if (!fs::is_directory(dataFolder, ec)) return report;
  std::vector<fs::path> leftovers;
  for (const auto& entry : fs::directory_iterator(dataFolder, ec))
    if (entry.path().filename().string().rfind(kPrefix, 0) == 0) leftovers.push_back(entry.path());
  for (const fs::path& folder : leftovers) {
    if (!isInside(dataFolder, folder) || fs::is_symlink(folder, ec) || !fs::is_directory(folder, ec)) {
      fs::remove(folder, ec);  // a stray file or link of that name: only the entry itself goes
      continue;
    }
    auto lock = lockFolder(folder, false);
    if (!lock) continue;  // an import running in another process
    std::string name;
    std::getline(std::ifstream(folder / kTargetFile), name);
    const fs::path staged = folder / "dataset";
    if (isSafeName(name) && fs::is_directory(staged, ec)) {
      auto target = confinedPath(dataFolder, {"datasets", name}, "staging target");
      auto record = db::findDataset(database, name);
      if (!record) return tl::unexpected(record.error());
      if (target && *record && !fs::exists(*target, ec) && isInside(*target, (*record)->volumePath)) {
        const fs::path stagedVolume = staged / fs::path((*record)->volumePath).filename();
        auto sum = db::checksumPath(stagedVolume.string());
        if (sum && *sum == (*record)->volumeChecksum) {
          fs::create_directories(target->parent_path(), ec);
          fs::rename(staged, *target, ec);
          if (!ec) report.completed.push_back(name);
        }
      }
    }
    fs::remove_all(folder, ec);
    ++report.removed;
  }
  return report;
}

void importCrashPoint(const char* point) {
  const char* wanted = std::getenv("AT_TEST_IMPORT_KILL_AT");
  if (wanted && std::strcmp(wanted, point) == 0) ::kill(::getpid(), SIGKILL);
}

}  // namespace at::app
