// Reading a tar into its entries and writing entries back as a tar (libarchive), for making
// altered course packages: a changed byte, a dropped entry, a newer manifest, hostile names.
#pragma once

#include <archive.h>
#include <archive_entry.h>

#include <filesystem>
#include <string>
#include <vector>

namespace at::test {

struct TarEntry {
  TarEntry() = default;
  TarEntry(std::string name_, std::string data_ = "", unsigned type_ = AE_IFREG, std::string symlink_ = "")
      : name(std::move(name_)), data(std::move(data_)), type(type_), symlink(std::move(symlink_)) {}
  std::string name;
  std::string data;           // regular files
  unsigned type = AE_IFREG;   // AE_IFREG, AE_IFLNK, AE_IFDIR, …
  std::string symlink;        // AE_IFLNK: the link's target
  std::string hardlink;       // a hard link to this earlier entry
};

inline std::vector<TarEntry> readTar(const std::filesystem::path& path) {
  std::vector<TarEntry> entries;
  archive* a = archive_read_new();
  archive_read_support_format_tar(a);
  archive_read_support_filter_all(a);
  if (archive_read_open_filename(a, path.c_str(), 1 << 16) == ARCHIVE_OK) {
    archive_entry* e = nullptr;
    while (archive_read_next_header(a, &e) == ARCHIVE_OK) {
      TarEntry t;
      t.name = archive_entry_pathname(e);
      t.type = archive_entry_filetype(e);
      std::string buffer(1 << 16, '\0');
      la_ssize_t n;
      while ((n = archive_read_data(a, buffer.data(), buffer.size())) > 0) t.data.append(buffer.data(), std::size_t(n));
      entries.push_back(std::move(t));
    }
  }
  archive_read_free(a);
  return entries;
}

// Writes `entries` as a pax tar (gzip-compressed when `gzip`).
inline void writeTar(const std::filesystem::path& path, const std::vector<TarEntry>& entries, bool gzip = false) {
  archive* a = archive_write_new();
  archive_write_set_format_pax_restricted(a);
  if (gzip) archive_write_add_filter_gzip(a);
  archive_write_open_filename(a, path.c_str());
  for (const TarEntry& t : entries) {
    archive_entry* e = archive_entry_new();
    archive_entry_set_pathname(e, t.name.c_str());
    archive_entry_set_perm(e, 0644);
    if (!t.hardlink.empty()) {
      archive_entry_set_filetype(e, AE_IFREG);
      archive_entry_set_hardlink(e, t.hardlink.c_str());
      archive_entry_set_size(e, 0);
    } else {
      archive_entry_set_filetype(e, t.type);
      if (t.type == AE_IFLNK) archive_entry_set_symlink(e, t.symlink.c_str());
      archive_entry_set_size(e, t.type == AE_IFREG ? la_int64_t(t.data.size()) : 0);
    }
    archive_write_header(a, e);
    if (t.type == AE_IFREG && t.hardlink.empty() && !t.data.empty()) archive_write_data(a, t.data.data(), t.data.size());
    archive_entry_free(e);
  }
  archive_write_close(a);
  archive_write_free(a);
}

// The entry called `name` (nullptr when absent).
inline TarEntry* findEntry(std::vector<TarEntry>& entries, const std::string& name) {
  for (TarEntry& e : entries)
    if (e.name == name) return &e;
  return nullptr;
}

}  // namespace at::test
