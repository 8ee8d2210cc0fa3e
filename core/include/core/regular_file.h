// Opening input files safely: only regular files are read. A FIFO would block the reader forever
// (nothing writes to it), a device such as /dev/zero or /dev/urandom never ends, a folder is not a
// file. The type is checked on the opened descriptor (O_NONBLOCK, so opening a FIFO does not wait),
// so a file swapped after a check cannot slip through.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "core/error.h"

namespace at {

// An open file descriptor, closed when it dies. Move-only.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) : fd_(fd) {}
  ~FileDescriptor();
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  FileDescriptor& operator=(FileDescriptor&& other) noexcept;
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  int get() const { return fd_; }
  // Gives up ownership (for APIs that take over the descriptor, such as zlib's gzdopen).
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_ = -1;
};

struct RegularFile {
  FileDescriptor fd;
  std::uint64_t sizeBytes = 0;
};

// Opens `path` for reading if it is a regular file (symbolic links followed). Errors start with
// `source`: "no such file", "is a folder", "is a FIFO (named pipe), not a regular file", "is a
// device, not a regular file", "cannot open the file (permission denied)".
Result<RegularFile> openRegularFile(const std::string& path, const std::string& source);

// Checks without keeping the file open (for libraries that open by name, such as DCMTK).
Status checkRegularFile(const std::string& path, const std::string& source);

// The whole content of a regular file of at most `maxBytes`.
Result<std::string> readRegularFile(const std::string& path, const std::string& source, std::size_t maxBytes);

// Reads up to `size` bytes at `offset` (fewer at the end of the file); an I/O error fails.
Result<std::string> readFileRange(const RegularFile& file, std::uint64_t offset, std::size_t size,
                                  const std::string& source);

}  // namespace at
