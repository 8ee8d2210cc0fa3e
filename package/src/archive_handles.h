// RAII owners of libarchive's reader and writer handles, and its error text.
#pragma once

#include <archive.h>

#include <memory>
#include <string>

namespace at::package {

struct ArchiveReadFree {
  void operator()(archive* a) const { archive_read_free(a); }
};
using ArchiveReader = std::unique_ptr<archive, ArchiveReadFree>;

struct ArchiveWriteFree {
  void operator()(archive* a) const { archive_write_free(a); }
};
using ArchiveWriter = std::unique_ptr<archive, ArchiveWriteFree>;

inline std::string archiveMessage(archive* a) {
  const char* message = archive_error_string(a);
  return message && *message ? message : "no detail given";
}

}  // namespace at::package
