// Writing files so that nobody ever sees half of one. Every file the program writes (label maps,
// distance fields, PNGs, exports, course packages, presets) goes through here:
//
//   - the output path is checked first: absent, or a regular file (a link is followed to the file it
//     names); a FIFO, device, socket or folder is refused at once, never opened (a FIFO would block);
//   - the bytes go to a temporary file in the same folder (".NAME.at-PID-N.part"), every write is
//     checked (a short write or ENOSPC/EIO is an error naming the file), the file is flushed to disk
//     (fsync) and closed (checked), then renamed over the old file and the folder is flushed;
//   - until the rename the old file is untouched; a failure removes the temporary file, and one left
//     behind by a killed process is removed by the next write of the same file.
//
// So after any failure or kill the path holds either the old content or the new, complete one.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "core/error.h"
#include "core/regular_file.h"

namespace at {

// Checks a path about to be written: absent (its folder must exist) or a regular file. Errors start
// with `source`: "is a FIFO (named pipe), not a regular file", "is a device, …", "is a folder, …",
// "the folder … does not exist".
Status checkOutputPath(const std::string& path, const std::string& source);

// A new version of one file, being written. Move-only; destroying it before commit() removes the
// temporary file and leaves the old file as it was.
class AtomicFile {
 public:
  // Checks `path` (checkOutputPath) and creates the temporary file beside it.
  static Result<AtomicFile> create(const std::string& path);

  AtomicFile(AtomicFile&& other) noexcept;
  AtomicFile& operator=(AtomicFile&& other) noexcept;
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();

  // Appends all of `bytes` (retrying short writes); a failed write is an error naming the file.
  // After a failure every further call fails the same way.
  Status write(std::string_view bytes);
  // Flushes to disk, closes, renames over the path and flushes the folder. Once only.
  Status commit();

  const std::string& path() const { return path_; }
  const std::string& temporaryPath() const { return temporary_; }

 private:
  AtomicFile() = default;
  void discard();

  std::string path_;       // the file the caller named (a link resolved to its target)
  std::string temporary_;  // empty once committed or discarded
  FileDescriptor fd_;
  std::string failure_;    // the first write error, repeated by later calls
};

// The whole of `content` as the new `path` (AtomicFile: create, write, commit).
Status writeFileAtomically(const std::string& path, std::string_view content);

}  // namespace at
