// Reading a course package: libarchive streams the tar's entries; each is checked against the
// manifest (name, type, size, SHA-256) while it is read, documents are kept in memory, data files
// go to fixed names in the extraction folder.
#include <archive.h>
#include <archive_entry.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "archive_handles.h"
#include "core/printable_text.h"
#include "core/safe_name.h"
#include "core/sha256.h"
#include "lessons/course_json.h"
#include "package/course_package.h"

namespace at::package {

namespace {

namespace fs = std::filesystem;

constexpr const char* kManifest = "manifest.json";
constexpr const char* kCourse = "course.json";
constexpr const char* kStructures = "dataset/structures.json";
constexpr const char* kLabels = "dataset/labels.nrrd";
constexpr const char* kVolume = "dataset/volume.nrrd";
constexpr const char* kPresetFolder = "presets/";

// The preset id of "presets/<id>.json", or "" for another name.
std::string presetIdOf(const std::string& path) {
  if (path.rfind(kPresetFolder, 0) != 0 || path.size() <= 5 + std::string(kPresetFolder).size()) return "";
  if (path.compare(path.size() - 5, 5, ".json") != 0) return "";
  const std::string id = path.substr(std::string(kPresetFolder).size(), path.size() - 5 - std::string(kPresetFolder).size());
  return id.find('/') == std::string::npos ? id : "";
}

bool dataFile(const std::string& path) { return path == kLabels || path == kVolume; }

// Why an entry name is unsafe, in words.
std::string unsafeNameReason(const std::string& name) {
  if (!name.empty() && name.front() == '/') return "an absolute path";
  if (name.find("..") != std::string::npos) return "a path outside the package ('..')";
  if (name.find('\\') != std::string::npos) return "a name with a backslash";
  return "not a plain relative name (letters, digits, '_', '-', '.', '/')";
}

// Checks the manifest's file list against what format version 1 holds.
Status checkListing(const Manifest& m, const std::string& name) {
  const auto listed = [&](const char* path) { return m.find(path) != nullptr; };
  if (!listed(kCourse)) return fail(name + ": manifest.json: files: course.json is not listed");
  for (const PackagedFile& f : m.files) {
    if (f.path != kCourse && f.path != kStructures && !dataFile(f.path) && presetIdOf(f.path).empty())
      return fail(name + ": manifest.json: files: '" + f.path + "' is not a file format version 1 holds");
    if (const std::string id = presetIdOf(f.path); !id.empty())
      if (auto ok = checkSafeName(name + ": manifest.json: files: " + f.path + ": preset id", id); !ok) return ok;
  }
  const bool builtin = m.dataset.source == VolumeSource::Builtin;
  if (builtin && (listed(kStructures) || listed(kLabels)))
    return fail(name + ": manifest.json: a built-in dataset's package holds no structures or labels");
  if (!builtin && !listed(kStructures)) return fail(name + ": manifest.json: files: dataset/structures.json is not listed");
  if ((m.dataset.source == VolumeSource::Included) != listed(kVolume))
    return fail(name + ": manifest.json: files: dataset/volume.nrrd " +
                (listed(kVolume) ? std::string("is listed but the dataset's source is ") + toString(m.dataset.source)
                                 : std::string("is not listed but the dataset is included")));
  return {};
}

class PackageReader {
 public:
  PackageReader(std::string name, const ReadOptions& options) : name_(std::move(name)), options_(options) {}
  ~PackageReader() {
    if (!done_)
      for (const fs::path& p : written_) fs::remove(p, ignored_);
  }

  Result<CoursePackage> read(archive* a) {
    archive_entry* entry = nullptr;
    int status = archive_read_next_header(a, &entry);
    if (status == ARCHIVE_EOF) return fail(name_ + ": empty archive: not a course package");
    if (status < ARCHIVE_WARN) return fail(name_ + ": not a course package (" + archiveMessage(a) + ")");
    const char* first = archive_entry_pathname(entry);
    if (!first || std::string(first) != kManifest)
      return fail(name_ + ": the first entry must be manifest.json, not '" + std::string(first ? first : "") +
                  "' (not a course package, or a damaged one)");
    auto manifestText = readDocument(a, entry, kManifest, nullptr);
    if (!manifestText) return tl::unexpected(manifestText.error());
    auto manifest = parseManifest(*manifestText, name_ + ": manifest.json");
    if (!manifest) return tl::unexpected(manifest.error());
    if (auto ok = checkListing(*manifest, name_); !ok) return tl::unexpected(ok.error());
    CoursePackage out;
    out.manifest = std::move(*manifest);

    std::uint64_t entries = 1;
    std::set<std::string> seen;
    std::map<std::string, std::string> documents;
    while (true) {
      status = archive_read_next_header(a, &entry);
      if (status == ARCHIVE_EOF) break;
      if (status < ARCHIVE_WARN)
        return fail(name_ + ": the archive is damaged or truncated after '" + lastEntry_ + "' (" + archiveMessage(a) + ")");
      if (++entries > options_.limits.maxEntries)
        return fail(name_ + ": more than " + std::to_string(options_.limits.maxEntries) + " entries");
      const char* raw = archive_entry_pathname(entry);
      const std::string path = raw ? raw : "";
      if (archive_entry_hardlink(entry) || archive_entry_filetype(entry) == AE_IFLNK)
        return fail(name_ + ": entry '" + path + "' is a link: packages hold regular files only");
      if (archive_entry_filetype(entry) != AE_IFREG)
        return fail(name_ + ": entry '" + path + "' is not a regular file: packages hold regular files only");
      if (!safeEntryName(path)) return fail(name_ + ": entry '" + path + "' is refused: " + unsafeNameReason(path));
      const PackagedFile* listed = out.manifest.find(path);
      if (!listed) return fail(name_ + ": entry '" + path + "' is not listed in the manifest");
      if (!seen.insert(path).second) return fail(name_ + ": entry '" + path + "' appears twice");
      lastEntry_ = path;
      if (dataFile(path)) {
        if (auto ok = readData(a, entry, *listed, out); !ok) return tl::unexpected(ok.error());
      } else {
        auto text = readDocument(a, entry, path, listed);
        if (!text) return tl::unexpected(text.error());
        documents[path] = std::move(*text);
      }
    }
    for (const PackagedFile& f : out.manifest.files)
      if (!seen.count(f.path))
        return fail(name_ + ": " + f.path + " is listed in the manifest but missing from the package");
    if (auto ok = interpret(documents, out); !ok) return tl::unexpected(ok.error());
    done_ = true;
    return out;
  }

 private:
  // Checks the entry's declared size against the manifest and the limits before reading a byte.
  Status checkSize(archive_entry* entry, const std::string& path, const PackagedFile* listed, std::uint64_t limit) {
    if (!archive_entry_size_is_set(entry)) return fail(name_ + ": entry '" + path + "' has no size");
    const std::int64_t size = archive_entry_size(entry);
    if (size < 0) return fail(name_ + ": entry '" + path + "' has a negative size");
    if (listed && std::uint64_t(size) != listed->size)
      return fail(name_ + ": " + path + ": " + std::to_string(size) + " bytes, but the manifest says " +
                  std::to_string(listed->size) + " (the package was altered or damaged)");
    if (std::uint64_t(size) > limit)
      return fail(name_ + ": " + path + ": " + std::to_string(size) + " bytes, more than the " + std::to_string(limit) +
                  " this reader accepts");
    total_ += std::uint64_t(size);
    if (total_ > options_.limits.maxTotalBytes)
      return fail(name_ + ": the entries hold more than " + std::to_string(options_.limits.maxTotalBytes) + " bytes");
    return {};
  }

  // Reads the entry through `sink`, hashing it; checks length and checksum against `listed`.
  template <class Sink>
  Status stream(archive* a, const std::string& path, std::uint64_t expected, const PackagedFile* listed, Sink&& sink) {
    Sha256 sha;
    std::vector<char> buffer(std::size_t(1) << 16);
    std::uint64_t got = 0;
    while (true) {
      const la_ssize_t n = archive_read_data(a, buffer.data(), buffer.size());
      if (n < 0) return fail(name_ + ": " + path + ": the archive is damaged or truncated (" + archiveMessage(a) + ")");
      if (n == 0) break;
      got += std::uint64_t(n);
      if (got > expected) return fail(name_ + ": " + path + ": longer than its declared size");
      sha.update(reinterpret_cast<const unsigned char*>(buffer.data()), std::size_t(n));
      if (auto ok = sink(buffer.data(), std::size_t(n)); !ok) return ok;
    }
    if (got != expected) return fail(name_ + ": " + path + ": truncated (" + std::to_string(got) + " of " + std::to_string(expected) + " bytes)");
    if (listed) {
      const std::string actual = sha.hex();
      if (actual != listed->sha256)
        return fail(name_ + ": " + path + ": checksum mismatch (the manifest says sha256:" + listed->sha256.substr(0, 16) +
                    "…, the file has sha256:" + actual.substr(0, 16) + "…): the package was altered or damaged");
    }
    return {};
  }

  Result<std::string> readDocument(archive* a, archive_entry* entry, const std::string& path, const PackagedFile* listed) {
    const ReadLimits& l = options_.limits;
    const std::uint64_t limit = path == kManifest ? l.maxManifestBytes
                                : path == kCourse ? l.maxCourseBytes
                                : path == kStructures ? l.maxStructuresBytes
                                                     : l.maxPresetBytes;
    if (auto ok = checkSize(entry, path, listed, limit); !ok) return tl::unexpected(ok.error());
    documentBytes_ += std::uint64_t(archive_entry_size(entry));
    if (documentBytes_ > l.maxDocumentsBytes)
      return fail(name_ + ": the documents (manifest, course, presets, structures) hold more than " +
                  std::to_string(l.maxDocumentsBytes) + " bytes together");
    std::string text;
    text.reserve(std::size_t(archive_entry_size(entry)));
    auto ok = stream(a, path, std::uint64_t(archive_entry_size(entry)), listed, [&](const char* data, std::size_t n) -> Status {
      text.append(data, n);
      return {};
    });
    if (!ok) return tl::unexpected(ok.error());
    return text;
  }

  Status readData(archive* a, archive_entry* entry, const PackagedFile& listed, CoursePackage& out) {
    // A data file holds at most the recorded grid's voxels at 2 bytes (int16 volume, uint16
    // labels) and an NRRD header: a package cannot make the importer write more than its content.
    std::uint64_t limit = options_.limits.maxDataBytes;
    if (const auto& g = out.manifest.dataset.geometry)
      limit = std::min<std::uint64_t>(limit, std::uint64_t(g->dims.count()) * 2 + (std::uint64_t(1) << 20));
    if (auto ok = checkSize(entry, listed.path, &listed, limit); !ok) return ok;
    const bool volume = listed.path == kVolume;
    std::ofstream file;
    fs::path target;
    if (options_.extractTo) {
      target = *options_.extractTo / (volume ? "volume.nrrd" : "labels.nrrd");
      file.open(target, std::ios::binary | std::ios::trunc);
      if (!file) return fail(ErrorKind::Io, target.string() + ": cannot create the file");
      written_.push_back(target);
    }
    auto ok = stream(a, listed.path, listed.size, &listed, [&](const char* data, std::size_t n) -> Status {
      if (!file.is_open()) return {};
      file.write(data, std::streamsize(n));
      if (!file) return fail(ErrorKind::Io, target.string() + ": writing failed (disk full?)");
      return {};
    });
    if (!ok) return ok;
    if (file.is_open()) {
      file.close();
      if (!file) return fail(ErrorKind::Io, target.string() + ": writing failed (disk full?)");
      (volume ? out.volumeFile : out.labelsFile) = target;
    }
    if (!volume) out.hasLabels = true;
    return {};
  }

  // The documents, parsed and checked against the manifest.
  Status interpret(const std::map<std::string, std::string>& documents, CoursePackage& out) {
    auto course = lessons::parseCourseJson(documents.at(kCourse), name_ + ": course.json");
    if (!course) return tl::unexpected(course.error());
    const Manifest& m = out.manifest;
    if (course->id != m.courseId || course->version != m.courseVersion || course->datasetId != m.dataset.name)
      return fail(name_ + ": manifest.json: course: says '" + m.courseId + "' version " + std::to_string(m.courseVersion) +
                  " on '" + m.dataset.name + "', but course.json is '" + course->id + "' version " +
                  std::to_string(course->version) + " on '" + course->datasetId + "'");
    out.courseJson = documents.at(kCourse);
    out.course = std::move(*course);
    for (const auto& [path, text] : documents) {
      const std::string id = presetIdOf(path);
      if (id.empty()) continue;
      auto preset = render::parsePreset(text, name_ + ": " + path);
      if (!preset) return tl::unexpected(preset.error());
      out.presets.push_back({id, *preset, text});
    }
    if (auto it = documents.find(kStructures); it != documents.end()) {
      auto structures = parseStructuresJson(it->second, name_ + ": " + kStructures);
      if (!structures) return tl::unexpected(structures.error());
      if (structures->empty()) return fail(name_ + ": " + kStructures + ": the dataset has no structure");
      out.structures = std::move(*structures);
    }
    return {};
  }

  std::string name_;
  const ReadOptions& options_;
  std::uint64_t total_ = 0, documentBytes_ = 0;
  std::string lastEntry_ = kManifest;
  std::vector<fs::path> written_;
  bool done_ = false;
  std::error_code ignored_;
};

ArchiveReader newReader() {
  ArchiveReader a(archive_read_new());
  if (a) {
    archive_read_support_format_tar(a.get());
    archive_read_support_filter_gzip(a.get());
  }
  return a;
}

}  // namespace

Result<CoursePackage> readPackageFile(const fs::path& file, const ReadOptions& options) {
  std::error_code ec;
  const auto status = fs::status(file, ec);
  if (ec || !fs::exists(status)) return fail(ErrorKind::NotFound, file.string() + ": no such file");
  if (!fs::is_regular_file(status)) return fail(file.string() + ": not a regular file");
  ArchiveReader a = newReader();
  if (!a) return fail(ErrorKind::Io, file.string() + ": out of memory opening the package");
  if (archive_read_open_filename(a.get(), file.c_str(), std::size_t(1) << 16) != ARCHIVE_OK)
    return fail(ErrorKind::Io, file.string() + ": cannot read (" + archiveMessage(a.get()) + ")");
  // Entry names, ids and parser messages quote the package's own bytes: one printable line.
  return withPrintableError(PackageReader(file.string(), options).read(a.get()));
}

Result<CoursePackage> readPackageBytes(std::string_view bytes, const std::string& name, const ReadOptions& options) {
  ArchiveReader a = newReader();
  if (!a) return fail(ErrorKind::Io, name + ": out of memory opening the package");
  if (archive_read_open_memory(a.get(), bytes.data(), bytes.size()) != ARCHIVE_OK)
    return fail(name + ": not a course package (" + archiveMessage(a.get()) + ")");
  return withPrintableError(PackageReader(name, options).read(a.get()));
}

}  // namespace at::package
