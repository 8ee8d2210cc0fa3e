// File and folder checksums over core/sha256.h (streaming: large volumes need no full copy in memory).
#include "db/checksum.h"

#include "core/printable_text.h"
#include "core/regular_file.h"
#include "core/sha256.h"
#include "volume/nrrd_io.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

namespace at::db {

namespace {

Status hashFile(Sha256& sha, const std::filesystem::path& file) {
  if (auto ok = checkRegularFile(file.string(), file.string()); !ok) return ok;
  std::ifstream in(file, std::ios::binary);
  if (!in) return fail(file.string() + ": cannot read");
  std::vector<char> buffer(1 << 20);
  while (in) {
    in.read(buffer.data(), std::streamsize(buffer.size()));
    const auto got = in.gcount();
    if (got > 0) sha.update(reinterpret_cast<const unsigned char*>(buffer.data()), std::size_t(got));
  }
  if (in.bad()) return fail(file.string() + ": read error");
  return {};
}

}  // namespace

Result<std::string> checksumPath(const std::string& path, const std::string& nrrdDataFolder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  Sha256 sha;
  if (fs::is_regular_file(path, ec)) {
    ImageLoadOptions options;
    options.dataFolder = nrrdDataFolder;
    auto dataFiles = nrrdDataFiles(path, options);
    if (!dataFiles) return tl::unexpected(dataFiles.error());
    if (!dataFiles->empty()) {
      // The header, then each data file in reading order: a separator no header ends with, its
      // size, a separator, its bytes. A file the header names again (LIST may repeat a name up to
      // a million times) is hashed once and then stands as the position of its first naming, so
      // the work is bounded by the folder's bytes, as for a DICOM folder.
      if (auto s = hashFile(sha, path); !s) return tl::unexpected(s.error());
      std::map<fs::path, std::size_t> firstNamed;
      for (std::size_t i = 0; i < dataFiles->size(); ++i) {
        const std::string& file = (*dataFiles)[i];
        std::error_code resolveError;  // (the loader's confinement check resolved it already)
        fs::path resolved = fs::weakly_canonical(file, resolveError);
        if (resolveError) resolved = file;
        const auto [first, isNew] = firstNamed.emplace(resolved, i);
        if (!isNew) {
          sha.update(std::string_view("\0again\0", 7));
          sha.update(std::to_string(first->second));
          continue;
        }
        sha.update(std::string_view("\0data\0", 6));
        sha.update(std::to_string(fs::file_size(file, ec)));
        sha.update(std::string_view("\0", 1));
        if (auto s = hashFile(sha, file); !s) return tl::unexpected(printableError(s.error()));  // names from the header
      }
      return "sha256:" + sha.hex();
    }
  }
  if (fs::is_directory(path, ec)) {
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(path, ec))
      if (entry.is_regular_file()) files.push_back(fs::relative(entry.path(), path));
    if (ec) return fail(path + ": cannot list: " + ec.message());
    std::sort(files.begin(), files.end());
    for (const auto& rel : files) {
      // Name and size (each ended by a byte that cannot occur in them), then the bytes.
      sha.update(rel.generic_string());
      sha.update(std::string_view("\0", 1));
      sha.update(std::to_string(fs::file_size(fs::path(path) / rel, ec)));
      sha.update(std::string_view("\0", 1));
      if (auto s = hashFile(sha, fs::path(path) / rel); !s) return tl::unexpected(s.error());
    }
  } else if (fs::is_regular_file(path, ec)) {
    if (auto s = hashFile(sha, path); !s) return tl::unexpected(s.error());
  } else {
    return fail(ErrorKind::NotFound, path + ": no such file or folder");
  }
  return "sha256:" + sha.hex();
}

Result<std::optional<std::string>> headerOnlyNrrdChecksum(const std::string& path, const std::string& nrrdDataFolder) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return std::optional<std::string>{};
  ImageLoadOptions options;
  options.dataFolder = nrrdDataFolder;
  auto dataFiles = nrrdDataFiles(path, options);
  if (!dataFiles || dataFiles->empty()) return std::optional<std::string>{};
  Sha256 sha;
  if (auto s = hashFile(sha, path); !s) return tl::unexpected(s.error());
  return std::optional<std::string>("sha256:" + sha.hex());
}

Result<std::string> checksumAsRecorded(const std::string& path, const std::string& recorded, const std::string& nrrdDataFolder) {
  auto now = checksumPath(path, nrrdDataFolder);
  if (!now || *now == recorded) return now;
  auto headerOnly = headerOnlyNrrdChecksum(path, nrrdDataFolder);
  if (headerOnly && *headerOnly && **headerOnly == recorded) return **headerOnly;
  return now;
}

}  // namespace at::db
