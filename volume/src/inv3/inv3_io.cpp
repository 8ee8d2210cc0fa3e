// InVesalius 3 project reader: libarchive walks the tar (gzip or plain), libplist parses main.plist.
//
// Sections: [archive] RAII handles and member search · [plist] reading main.plist's fields ·
// [load] loadInv3.
#include "volume/inv3_io.h"

#include <archive.h>
#include <archive_entry.h>
#include <plist/plist.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/printable_text.h"
#include "core/regular_file.h"
#include "load_limits.h"
#include "plist_depth.h"
#include "raw_values.h"

namespace at {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// [archive]

struct ArchiveReadFree {
  void operator()(archive* a) const { archive_read_free(a); }
};
using ArchiveReader = std::unique_ptr<archive, ArchiveReadFree>;

constexpr std::size_t kMaxPlistBytes = std::size_t(1) << 20;  // InVesalius writes about 2 KB
constexpr std::size_t kReadChunkBytes = std::size_t(4) << 20;
// A project holds main.plist, the matrix and a few files per mask, surface and measurement:
// tens of members with short names. More, or longer names, are refused before they cost time or
// memory.
constexpr std::size_t kMaxMembers = 4096;
constexpr std::size_t kMaxMemberNameBytes = 1024;
const std::string kMainPlist = "main.plist";

std::string archiveMessage(archive* a) {
  const char* message = archive_error_string(a);
  return message && *message ? message : "no detail given";
}

// One pass over the archive's members. A project is read in two passes (main.plist, then the
// matrix it names), because InVesalius writes the members in no fixed order.
class MemberReader {
 public:
  explicit MemberReader(std::string path) : path_(std::move(path)) {}

  Status open() {
    if (!std::ifstream(path_, std::ios::binary)) return fail(ErrorKind::Io, path_ + ": cannot open the file for reading");
    reader_.reset(archive_read_new());
    if (!reader_) return fail(ErrorKind::Io, path_ + ": out of memory opening the archive");
    archive_read_support_filter_all(reader_.get());
    archive_read_support_format_tar(reader_.get());
    // Opening reads ahead: an unknown format or a short gzip stream fails here.
    if (archive_read_open_filename(reader_.get(), path_.c_str(), 1 << 16) != ARCHIVE_OK) return fail(notAProject());
    return {};
  }

  // Advances to the first regular file whose path satisfies `wanted`; false when the archive ends
  // first. Members passed over are remembered for messages.
  Result<bool> seek(const std::function<bool(const std::string&)>& wanted) {
    while (true) {
      archive_entry* entry = nullptr;
      const int status = archive_read_next_header(reader_.get(), &entry);
      if (status == ARCHIVE_EOF) return false;
      if (status < ARCHIVE_WARN) {
        if (!readAny_) return fail(notAProject());
        return fail(path_ + ": the archive is damaged or truncated after member '" + lastSeen_ + "' (" +
                    archiveMessage(reader_.get()) + ")");
      }
      readAny_ = true;
      if (++members_ > kMaxMembers)
        return fail(path_ + ": more than " + std::to_string(kMaxMembers) + " members: not an InVesalius project");
      const char* name = archive_entry_pathname(entry);
      const std::string_view raw = name ? std::string_view(name) : std::string_view();
      if (raw.size() > kMaxMemberNameBytes)
        return fail(path_ + ": member " + std::to_string(members_) + " has a name of " + std::to_string(raw.size()) +
                    " bytes (at most " + std::to_string(kMaxMemberNameBytes) + "): not an InVesalius project");
      const std::string member(raw);
      lastSeen_ = member;
      if (seen_.size() < 8) seen_.push_back(member);
      if (archive_entry_filetype(entry) == AE_IFREG && wanted(member)) {
        current_ = member;
        declaredSize_ = archive_entry_size_is_set(entry) ? std::optional<std::int64_t>(archive_entry_size(entry)) : std::nullopt;
        return true;
      }
    }
  }

  // The member seek() stopped at.
  const std::string& current() const { return current_; }
  // The size the current member's header declares, if it declares one.
  std::optional<std::int64_t> declaredSize() const { return declaredSize_; }

  // Reads the current member whole; fails with `tooLarge` when it holds more than `maxBytes`.
  // `onChunk` (optional) gets the bytes read so far after each chunk and may stop the read by
  // returning an error.
  Result<std::string> readCurrent(std::size_t maxBytes, const std::string& tooLarge,
                                  const std::function<Status(std::size_t)>& onChunk = {}) {
    std::string bytes;
    // A chunk the size the member declares (one more byte to see the end), 4 KiB to 4 MiB: a
    // small main.plist does not cost a zeroed 4 MiB buffer. A false declaration only changes how
    // many chunks are read.
    std::size_t chunkBytes = kReadChunkBytes;
    if (declaredSize_ && *declaredSize_ >= 0 && std::uint64_t(*declaredSize_) < kReadChunkBytes)
      chunkBytes = std::max<std::size_t>(std::size_t(*declaredSize_) + 1, std::size_t(4) << 10);
    std::string chunk(chunkBytes, '\0');
    while (true) {
      const la_ssize_t got = archive_read_data(reader_.get(), chunk.data(), chunk.size());
      if (got < 0)
        return fail(path_ + ": the archive is damaged or truncated in member '" + current_ + "' (" +
                    archiveMessage(reader_.get()) + ")");
      if (got == 0) return bytes;
      if (bytes.size() + std::size_t(got) > maxBytes)
        return fail(tooLarge);
      bytes.append(chunk.data(), std::size_t(got));
      if (onChunk)
        if (auto ok = onChunk(bytes.size()); !ok) return tl::unexpected(ok.error());
    }
  }

  // "a/main.plist, a/matrix.dat, …" (the first few), for messages.
  std::string seenList() const {
    if (seen_.empty()) return "none";
    std::string list;
    for (std::size_t n = 0; n < seen_.size(); ++n) list += (n ? ", " : "") + seen_[n];
    if (members_ > seen_.size()) list += ", and " + std::to_string(members_ - seen_.size()) + " more";
    return list;
  }

 private:
  std::string notAProject() const {
    return path_ + ": not an InVesalius project, or a damaged one (expected a tar archive, gzip-compressed or plain: " +
           archiveMessage(reader_.get()) + ")";
  }

  std::string path_;
  ArchiveReader reader_;
  bool readAny_ = false;
  std::vector<std::string> seen_;  // the first 8 members' names, for messages
  std::size_t members_ = 0;
  std::string lastSeen_;
  std::string current_;
  std::optional<std::int64_t> declaredSize_;
};

std::string baseName(const std::string& member) {
  const std::size_t slash = member.find_last_of('/');
  return slash == std::string::npos ? member : member.substr(slash + 1);
}

std::string folderOf(const std::string& member) {
  const std::size_t slash = member.find_last_of('/');
  return slash == std::string::npos ? std::string() : member.substr(0, slash + 1);
}

// ---------------------------------------------------------------------------------------------
// [plist]

struct PlistFree {
  void operator()(void* node) const { plist_free(static_cast<plist_t>(node)); }
};
using PlistRoot = std::unique_ptr<void, PlistFree>;

struct ProjectHeader {
  std::array<long long, 3> shapeZyx{0, 0, 0};
  Vec3 spacingXyz{1, 1, 1};
  ScalarKind kind = ScalarKind::Int16;
  std::string matrixFile;
  std::string modality;
  std::string orientation;   // InVesalius' acquisition orientation, when written as text
  long long formatVersion = -1;
  bool hasAffine = false;
};

// libplist 2.2 stores every integer as PLIST_UINT; negative ones come back as their 64-bit
// two's complement.
std::optional<long long> integerOf(plist_t node) {
  if (!node || plist_get_node_type(node) != PLIST_UINT) return std::nullopt;
  std::uint64_t value = 0;
  plist_get_uint_val(node, &value);
  return static_cast<long long>(value);
}

std::optional<double> numberOf(plist_t node) {
  if (!node) return std::nullopt;
  if (plist_get_node_type(node) == PLIST_REAL) {
    double value = 0;
    plist_get_real_val(node, &value);
    return value;
  }
  if (auto integer = integerOf(node)) return double(*integer);
  return std::nullopt;
}

std::optional<std::string> stringOf(plist_t node) {
  if (!node || plist_get_node_type(node) != PLIST_STRING) return std::nullopt;
  const char* text = plist_get_string_ptr(node, nullptr);
  return text ? std::optional<std::string>(text) : std::nullopt;
}

std::optional<ScalarKind> kindOfDtype(const std::string& dtype) {
  static const std::pair<const char*, ScalarKind> kinds[] = {
      {"int8", ScalarKind::Int8},   {"uint8", ScalarKind::UInt8},   {"int16", ScalarKind::Int16},
      {"uint16", ScalarKind::UInt16}, {"int32", ScalarKind::Int32}, {"uint32", ScalarKind::UInt32},
      {"float32", ScalarKind::Float32}, {"float64", ScalarKind::Float64}};
  for (const auto& [name, kind] : kinds)
    if (dtype == name) return kind;
  return std::nullopt;
}

Result<ProjectHeader> parseMainPlist(const std::string& path, const std::string& member, const std::string& bytes) {
  const std::string where = path + ": " + member;
  if (bytes.size() > std::numeric_limits<std::uint32_t>::max()) return fail(where + " is too large");
  // libplist recurses once per level: a deeply nested plist would overflow the stack.
  if (auto ok = inv3::checkPlistDepth(bytes, where); !ok) return tl::unexpected(ok.error());
  plist_t raw = nullptr;
  plist_from_memory(bytes.data(), std::uint32_t(bytes.size()), &raw);
  PlistRoot root(raw);
  if (!raw) return fail(where + " is not a property list (XML or binary plist)");
  if (plist_get_node_type(raw) != PLIST_DICT) return fail(where + ": the property list is not a dictionary");

  ProjectHeader h;
  plist_t matrix = plist_dict_get_item(raw, "matrix");
  if (!matrix || plist_get_node_type(matrix) != PLIST_DICT)
    return fail(where + ": no 'matrix' dictionary (this may be a project from InVesalius before 3.0, which is not supported)");

  plist_t shape = plist_dict_get_item(matrix, "shape");
  const std::string shapeRule = "'matrix.shape' must be 3 positive integers (z, y, x) of at most 65535";
  if (!shape || plist_get_node_type(shape) != PLIST_ARRAY || plist_array_get_size(shape) != 3)
    return fail(where + ": " + shapeRule);
  for (std::uint32_t a = 0; a < 3; ++a) {
    const auto n = integerOf(plist_array_get_item(shape, a));
    if (!n || *n <= 0 || *n > 65535) return fail(where + ": " + shapeRule);
    h.shapeZyx[a] = *n;
  }

  const auto dtype = stringOf(plist_dict_get_item(matrix, "dtype"));
  if (!dtype) return fail(where + ": 'matrix.dtype' is missing or not a string");
  const auto kind = kindOfDtype(*dtype);
  if (!kind)
    return fail(where + ": unsupported 'matrix.dtype' '" + *dtype +
                "' (supported: int8, uint8, int16, uint16, int32, uint32, float32, float64)");
  h.kind = *kind;

  const auto file = stringOf(plist_dict_get_item(matrix, "filename"));
  if (!file || file->empty() || file->find('/') != std::string::npos || *file == "." || *file == "..")
    return fail(where + ": 'matrix.filename' must name a member beside main.plist (e.g. matrix.dat)");
  h.matrixFile = *file;

  plist_t spacing = plist_dict_get_item(raw, "spacing");
  const std::string spacingRule = "'spacing' must be 3 positive numbers in mm (x, y, z)";
  if (!spacing || plist_get_node_type(spacing) != PLIST_ARRAY || plist_array_get_size(spacing) != 3)
    return fail(where + ": " + spacingRule);
  for (std::uint32_t a = 0; a < 3; ++a) {
    const auto mm = numberOf(plist_array_get_item(spacing, a));
    if (!mm || !std::isfinite(*mm) || *mm <= 0) return fail(where + ": " + spacingRule);
    h.spacingXyz[a] = *mm;
  }

  h.modality = stringOf(plist_dict_get_item(raw, "modality")).value_or("");
  h.orientation = stringOf(plist_dict_get_item(raw, "orientation")).value_or("");
  h.formatVersion = integerOf(plist_dict_get_item(raw, "format_version")).value_or(-1);
  plist_t affine = plist_dict_get_item(raw, "affine");
  h.hasAffine = affine && plist_get_node_type(affine) == PLIST_ARRAY && plist_array_get_size(affine) > 0;
  return h;
}

// InVesalius' axes in LPS: i → left, j → anterior, k → superior; the grid centred on (0,0,0) mm
// because the project stores no position.
Geometry projectGeometry(const ProjectHeader& h) {
  Geometry g;
  g.dims = {int(h.shapeZyx[2]), int(h.shapeZyx[1]), int(h.shapeZyx[0])};
  g.spacingMm = h.spacingXyz;
  g.direction.m = {{{1, 0, 0}, {0, -1, 0}, {0, 0, 1}}};
  const Vec3 halfIndex{(g.dims.x - 1) / 2.0, (g.dims.y - 1) / 2.0, (g.dims.z - 1) / 2.0};
  const Vec3 centre = g.direction * Vec3{halfIndex[0] * g.spacingMm[0], halfIndex[1] * g.spacingMm[1], halfIndex[2] * g.spacingMm[2]};
  g.originMm = {-centre[0], -centre[1], -centre[2]};
  return g;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// [load]

namespace {

Result<LoadedImage> readInv3(const std::string& path, const ImageLoadOptions& options) {
  // A FIFO would block the archive reader; a device would never end.
  if (auto regular = checkRegularFile(path, path); !regular) return tl::unexpected(regular.error());

  // Pass 1: main.plist.
  MemberReader first(path);
  if (auto ok = first.open(); !ok) return tl::unexpected(ok.error());
  auto found = first.seek([](const std::string& member) { return baseName(member) == kMainPlist; });
  if (!found) return tl::unexpected(found.error());
  if (!*found)
    return fail(path + ": no main.plist in the archive, so not an InVesalius 3 project (members: " + first.seenList() + ")");
  const std::string plistMember = first.current();
  auto plistBytes = first.readCurrent(kMaxPlistBytes, path + ": " + plistMember + " holds more than " +
                                                          std::to_string(kMaxPlistBytes) + " bytes, too many for a project header");
  if (!plistBytes) return tl::unexpected(plistBytes.error());
  auto header = parseMainPlist(path, plistMember, *plistBytes);
  if (!header) return tl::unexpected(header.error());
  const ProjectHeader& h = *header;

  LoadedImage loaded;
  loaded.storedKind = h.kind;
  loaded.image.geometry = projectGeometry(h);
  const Dims dims = loaded.image.geometry.dims;
  // Pass 2 holds the stored matrix (its buffer may briefly double as it grows) and a read chunk
  // beside the floats.
  const std::size_t needBytes = dims.count() * detail::bytesOf(h.kind);
  if (auto fits = detail::checkImageFits(path, dims, 2.0 * double(needBytes) + double(kReadChunkBytes), options); !fits)
    return tl::unexpected(fits.error());

  // Pass 2: the matrix beside main.plist.
  const std::string matrixMember = folderOf(plistMember) + h.matrixFile;
  const std::string sizeText = "shape " + std::to_string(h.shapeZyx[0]) + "x" + std::to_string(h.shapeZyx[1]) + "x" +
                               std::to_string(h.shapeZyx[2]) + " (z,y,x) × " + toString(h.kind) + " needs " +
                               std::to_string(needBytes) + " bytes";
  MemberReader second(path);
  if (auto ok = second.open(); !ok) return tl::unexpected(ok.error());
  found = second.seek([&](const std::string& member) { return member == matrixMember; });
  if (!found) return tl::unexpected(found.error());
  if (!*found)
    return fail(path + ": main.plist names the matrix '" + h.matrixFile + "' but the archive has no member '" +
                matrixMember + "' (members: " + second.seenList() + ")");
  if (const auto declared = second.declaredSize(); declared && *declared != std::int64_t(needBytes))
    return fail(path + ": " + matrixMember + " holds " + std::to_string(*declared) + " bytes but " + sizeText);
  if (options.progress) options.progress(0, needBytes);
  auto matrix = second.readCurrent(needBytes, path + ": " + matrixMember + " holds more bytes than " + sizeText,
                                   [&](std::size_t done) -> Status {
    if (detail::loadCancelled(options)) return tl::unexpected(detail::cancelledError(path));
    if (options.progress) options.progress(done, needBytes);
    return {};
  });
  if (!matrix) return tl::unexpected(matrix.error());
  if (matrix->size() != needBytes)
    return fail(path + ": " + matrixMember + " holds " + std::to_string(matrix->size()) + " bytes but " + sizeText);

  // numpy's C order (z, y, x) is this grid's order (i = x contiguous); the values are little endian.
  loaded.image.voxels.resize(dims.count());
  detail::decodeRawValues(*matrix, h.kind, std::endian::native == std::endian::big, loaded.image.voxels);

  std::string note = "InVesalius project";
  if (h.formatVersion >= 0) note += " (format " + std::to_string(h.formatVersion) + ")";
  if (!h.modality.empty()) note += ", modality " + h.modality;
  if (!h.orientation.empty()) note += ", acquired " + h.orientation;
  loaded.notes.push_back(note);
  loaded.notes.push_back("no patient position is stored: axes placed as InVesalius keeps them (x → left, "
                         "y → anterior, z → superior), the grid centred on (0,0,0) mm");
  if (h.hasAffine) loaded.notes.push_back("the project's 'affine' (from a NIfTI import) is not applied");
  return loaded;
}

}  // namespace

// Names and values quoted from the project (member names, plist strings) may hold any bytes.
Result<LoadedImage> loadInv3(const std::string& path, const ImageLoadOptions& options) {
  return withPrintableError(readInv3(path, options));
}

}  // namespace at
