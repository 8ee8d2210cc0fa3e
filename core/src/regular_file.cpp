#include "core/regular_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace at {

FileDescriptor::~FileDescriptor() {
  if (fd_ >= 0) ::close(fd_);
}

FileDescriptor& FileDescriptor::operator=(FileDescriptor&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

namespace {

const char* notRegularProblem(mode_t mode) {
  if (S_ISDIR(mode)) return "is a folder, not a file";
  if (S_ISFIFO(mode)) return "is a FIFO (named pipe), not a regular file";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "is a device, not a regular file";
  if (S_ISSOCK(mode)) return "is a socket, not a regular file";
  return "is not a regular file";
}

}  // namespace

Result<RegularFile> openRegularFile(const std::string& path, const std::string& source) {
  // O_NONBLOCK: opening a FIFO with no writer returns at once instead of waiting for one.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    const int error = errno;
    if (error == ENOENT || error == ENOTDIR) return fail(ErrorKind::NotFound, source + ": no such file");
    return fail(ErrorKind::Io, source + ": cannot open the file (" + std::strerror(error) + ")");
  }
  RegularFile file{FileDescriptor(fd), 0};
  struct stat info {};
  if (::fstat(fd, &info) != 0)
    return fail(ErrorKind::Io, source + ": cannot read the file's type (" + std::strerror(errno) + ")");
  if (!S_ISREG(info.st_mode)) return fail(source + ": " + notRegularProblem(info.st_mode));
  // Back to blocking reads for the regular file.
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
  file.sizeBytes = std::uint64_t(info.st_size);
  return file;
}

Status checkRegularFile(const std::string& path, const std::string& source) {
  auto file = openRegularFile(path, source);
  if (!file) return tl::unexpected(file.error());
  return {};
}

Result<std::string> readFileRange(const RegularFile& file, std::uint64_t offset, std::size_t size,
                                  const std::string& source) {
  std::string bytes;
  bytes.resize(size);
  std::size_t done = 0;
  while (done < size) {
    const ssize_t got = ::pread(file.fd.get(), bytes.data() + done, size - done, off_t(offset + done));
    if (got < 0) {
      if (errno == EINTR) continue;
      return fail(ErrorKind::Io, source + ": cannot read the file (" + std::strerror(errno) + ")");
    }
    if (got == 0) break;
    done += std::size_t(got);
  }
  bytes.resize(done);
  return bytes;
}

Result<std::string> readRegularFile(const std::string& path, const std::string& source, std::size_t maxBytes) {
  auto file = openRegularFile(path, source);
  if (!file) return tl::unexpected(file.error());
  if (file->sizeBytes > maxBytes)
    return fail(source + ": the file holds " + std::to_string(file->sizeBytes) + " bytes, more than the " +
                std::to_string(maxBytes) + " this reader accepts");
  // A file growing while it is read is read up to the size it had when opened.
  return readFileRange(*file, 0, std::size_t(file->sizeBytes), source);
}

}  // namespace at
