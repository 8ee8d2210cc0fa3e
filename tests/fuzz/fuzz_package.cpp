// Course packages (.atcourse) through readPackageBytes, extracting into a scratch folder. Two
// shapes of input:
//  - an archive (anything not starting with '{'): the bytes as a package — libarchive's tar and
//    gzip reading, the first-entry and entry-name checks, sizes, checksums, limits;
//  - an assembled package (input starting with '{'): parts split at "--8<--" lines, the first the
//    manifest's JSON, each further one "NAME\nCONTENT" an entry. The harness writes them into a
//    tar with libarchive after setting each listed file's size and SHA-256 in the manifest to the
//    entry's real ones, so that mutations of the manifest, course, presets and structures reach
//    the parsers behind the checksum check instead of stopping at it.
// Either way the reader must return a package or a one-line error naming it, and on error leave
// nothing in the extraction folder.
#include <archive.h>
#include <archive_entry.h>

#include <nlohmann/json.hpp>

#include "core/sha256.h"
#include "fuzz_support.h"
#include "package/course_package.h"

namespace {

using namespace at;

struct ArchiveWriteFree {
  void operator()(archive* a) const { archive_write_free(a); }
};

la_ssize_t appendToString(archive*, void* out, const void* buffer, std::size_t length) {
  static_cast<std::string*>(out)->append(static_cast<const char*>(buffer), length);
  return la_ssize_t(length);
}

struct Entry {
  std::string name;
  std::string_view content;
};

// The manifest text with every listed file's size and sha256 set to those of the entry of that
// name (the text unchanged when it is no JSON object with a files array).
std::string fixedManifest(std::string_view text, const std::vector<Entry>& entries) {
  nlohmann::json manifest = nlohmann::json::parse(text, nullptr, false);
  if (manifest.is_discarded() || !manifest.is_object() || !manifest.contains("files") || !manifest["files"].is_array())
    return std::string(text);
  for (auto& file : manifest["files"]) {
    if (!file.is_object() || !file.contains("path") || !file["path"].is_string()) continue;
    const std::string path = file["path"].get<std::string>();
    for (const Entry& e : entries)
      if (e.name == path) {
        file["size"] = e.content.size();
        file["sha256"] = sha256Hex(e.content);
        break;
      }
  }
  return manifest.dump(1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// A POSIX tar of manifest.json and the entries ("" when libarchive refuses to write it).
std::string tarOf(const std::string& manifest, const std::vector<Entry>& entries) {
  std::string bytes;
  std::unique_ptr<archive, ArchiveWriteFree> a(archive_write_new());
  if (!a || archive_write_set_format_pax_restricted(a.get()) != ARCHIVE_OK ||
      archive_write_open(a.get(), &bytes, nullptr, appendToString, nullptr) != ARCHIVE_OK)
    return "";
  const auto add = [&](const std::string& name, std::string_view content) {
    std::unique_ptr<archive_entry, void (*)(archive_entry*)> entry(archive_entry_new(), archive_entry_free);
    archive_entry_set_pathname(entry.get(), name.c_str());
    archive_entry_set_filetype(entry.get(), AE_IFREG);
    archive_entry_set_perm(entry.get(), 0644);
    archive_entry_set_size(entry.get(), la_int64_t(content.size()));
    if (archive_write_header(a.get(), entry.get()) != ARCHIVE_OK) return false;
    return archive_write_data(a.get(), content.data(), content.size()) == la_ssize_t(content.size());
  };
  if (!add("manifest.json", manifest)) return "";
  for (const Entry& e : entries)
    if (!add(e.name, e.content)) return "";
  if (archive_write_close(a.get()) != ARCHIVE_OK) return "";
  return bytes;
}

std::string assembled(const std::uint8_t* data, std::size_t size) {
  const auto parts = fuzz::splitParts(data, size, 16);
  std::vector<Entry> entries;
  for (std::size_t i = 1; i < parts.size(); ++i) {
    const std::size_t newline = parts[i].find('\n');
    if (newline == std::string_view::npos || newline == 0) continue;
    entries.push_back({std::string(parts[i].substr(0, newline)), parts[i].substr(newline + 1)});
  }
  return tarOf(fixedManifest(parts[0], entries), entries);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const bool assemble = size > 0 && data[0] == '{';
  const std::string bytes =
      assemble ? assembled(data, size) : std::string(reinterpret_cast<const char*>(data), size);
  if (assemble && bytes.empty()) return 0;  // libarchive would not write these entries

  const std::filesystem::path& extract = fuzz::Scratch::instance().fresh();
  package::ReadOptions options;
  options.extractTo = extract;
  options.limits.maxCourseBytes = options.limits.maxStructuresBytes = std::uint64_t(1) << 20;
  options.limits.maxDataBytes = fuzz::kLoaderMaxBytes;
  options.limits.maxTotalBytes = 2 * fuzz::kLoaderMaxBytes;
  const std::string name = "fuzz.atcourse";
  const auto read = package::readPackageBytes(bytes, name, options);
  fuzz::checkResult(read, name);
  // AT_FUZZ_PRINT=1 shows what each input gave (to check that the seeds read as packages).
  static const bool print = std::getenv("AT_FUZZ_PRINT") != nullptr;
  if (print) std::fprintf(stderr, "fuzz_package: %s\n", read ? ("read course " + read->course.id).c_str() : read.error().message.c_str());
  if (!read) {
    std::error_code ec;
    fuzz::expect(std::filesystem::is_empty(extract, ec), "a refused package leaves nothing in the extraction folder");
  } else {
    fuzz::expect(read->course.id == read->manifest.courseId, "the course is the one the manifest names");
    fuzz::expect(read->volumeFile.empty() || std::filesystem::is_regular_file(read->volumeFile),
                 "an extracted volume exists");
  }
  return 0;
}
