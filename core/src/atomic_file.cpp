#include "core/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

namespace at {

namespace {

const char* notRegularProblem(mode_t mode) {
  if (S_ISDIR(mode)) return "is a folder, not a file";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe), not a regular file";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "is a device, not a regular file";
  if (S_ISSOCK(mode)) return "is a socket, not a regular file";
  return "is not a regular file";
}

std::string folderOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return path.substr(0, slash);
}

std::string nameOf(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string systemError(int error) { return std::strerror(error); }

// ".NAME.at-" — the start of every temporary file of NAME; the pid and a counter follow, then ".part".
std::string temporaryPrefix(const std::string& name) { return "." + name + ".at-"; }

// Removes temporary files of `name` left in `folder` by processes that no longer run (killed while
// writing). Files of running processes (another writer at this moment) are left alone.
void removeStaleTemporaries(const std::string& folder, const std::string& name) {
  DIR* dir = ::opendir(folder.c_str());
  if (!dir) return;
  const std::string prefix = temporaryPrefix(name);
  while (const dirent* entry = ::readdir(dir)) {
    const std::string entryName = entry->d_name;
    if (entryName.size() <= prefix.size() + 5 || entryName.compare(0, prefix.size(), prefix) != 0 ||
        entryName.compare(entryName.size() - 5, 5, ".part") != 0)
      continue;
    const long pid = std::strtol(entryName.c_str() + prefix.size(), nullptr, 10);
    if (pid <= 0 || pid == long(::getpid())) continue;
    if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue;
    ::unlink((folder + "/" + entryName).c_str());
  }
  ::closedir(dir);
}

void syncFolder(const std::string& folder) {
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);  // some file systems refuse fsync on a folder (EINVAL); the rename is done either way
  ::close(fd);
}

}  // namespace

Status checkOutputPath(const std::string& path, const std::string& source) {
  if (path.empty()) return fail(source + ": the file name is empty");
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0) {
    if (!S_ISREG(info.st_mode)) return fail(source + ": " + notRegularProblem(info.st_mode));
    return {};
  }
  const int error = errno;
  if (error != ENOENT) return fail(ErrorKind::Io, source + ": cannot write here (" + systemError(error) + ")");
  struct stat lnk {};
  if (::lstat(path.c_str(), &lnk) == 0 && S_ISLNK(lnk.st_mode))
    return fail(source + ": is a link to a file that does not exist");
  const std::string folder = folderOf(path);
  struct stat folderInfo {};
  if (::stat(folder.c_str(), &folderInfo) != 0)
    return fail(ErrorKind::NotFound, source + ": the folder '" + folder + "' does not exist");
  if (!S_ISDIR(folderInfo.st_mode)) return fail(source + ": '" + folder + "' is not a folder");
  return {};
}

Result<AtomicFile> AtomicFile::create(const std::string& path) {
  if (auto ok = checkOutputPath(path, path); !ok) return tl::unexpected(ok.error());
  AtomicFile file;
  file.path_ = path;
  // A link is followed: the file it names gets the new content and the link stays.
  struct stat lnk {};
  if (::lstat(path.c_str(), &lnk) == 0 && S_ISLNK(lnk.st_mode)) {
    char resolved[PATH_MAX];
    if (!::realpath(path.c_str(), resolved))
      return fail(ErrorKind::Io, path + ": cannot resolve the link (" + systemError(errno) + ")");
    file.path_ = resolved;
  }
  const std::string folder = folderOf(file.path_), name = nameOf(file.path_);
  removeStaleTemporaries(folder, name);
  static std::atomic<unsigned> counter{0};
  for (int attempt = 0; attempt < 100; ++attempt) {
    const std::string temporary = folder + "/" + temporaryPrefix(name) + std::to_string(::getpid()) + "-" +
                                  std::to_string(counter.fetch_add(1)) + ".part";
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC | O_NOCTTY, 0666);
    if (fd >= 0) {
      file.fd_ = FileDescriptor(fd);
      file.temporary_ = temporary;
      return file;
    }
    if (errno != EEXIST)
      return fail(ErrorKind::Io, path + ": cannot create a file in '" + folder + "' (" + systemError(errno) + ")");
  }
  return fail(ErrorKind::Io, path + ": cannot create a temporary file in '" + folder + "'");
}

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : path_(std::move(other.path_)),
      temporary_(std::move(other.temporary_)),
      fd_(std::move(other.fd_)),
      failure_(std::move(other.failure_)) {
  other.temporary_.clear();
}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
  if (this != &other) {
    discard();
    path_ = std::move(other.path_);
    temporary_ = std::move(other.temporary_);
    fd_ = std::move(other.fd_);
    failure_ = std::move(other.failure_);
    other.temporary_.clear();
  }
  return *this;
}

AtomicFile::~AtomicFile() { discard(); }

void AtomicFile::discard() {
  fd_ = FileDescriptor();
  if (!temporary_.empty()) ::unlink(temporary_.c_str());
  temporary_.clear();
}

Status AtomicFile::write(std::string_view bytes) {
  if (!failure_.empty()) return fail(ErrorKind::Io, failure_);
  if (temporary_.empty()) return fail(ErrorKind::Io, path_ + ": the file was already finished");
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_.get(), bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      failure_ = path_ + ": cannot write (" + systemError(errno) + "); the old file is kept";
      return fail(ErrorKind::Io, failure_);
    }
    done += std::size_t(n);
  }
  return {};
}

Status AtomicFile::commit() {
  if (!failure_.empty()) return fail(ErrorKind::Io, failure_);
  if (temporary_.empty()) return fail(ErrorKind::Io, path_ + ": the file was already finished");
  const auto failed = [&](const std::string& what) {
    failure_ = path_ + ": " + what + " (" + systemError(errno) + "); the old file is kept";
    discard();
    return fail(ErrorKind::Io, failure_);
  };
  if (::fsync(fd_.get()) != 0) return failed("cannot flush the file to disk");
  // close() can report a delayed write error (NFS, quota): checked, so that the descriptor is
  // released here rather than by the owner.
  if (::close(fd_.release()) != 0) return failed("cannot finish writing");
  if (::rename(temporary_.c_str(), path_.c_str()) != 0) return failed("cannot put the new file in place");
  temporary_.clear();
  syncFolder(folderOf(path_));
  return {};
}

Status writeFileAtomically(const std::string& path, std::string_view content) {
  auto file = AtomicFile::create(path);
  if (!file) return tl::unexpected(file.error());
  if (auto ok = file->write(content); !ok) return ok;
  return file->commit();
}

}  // namespace at
