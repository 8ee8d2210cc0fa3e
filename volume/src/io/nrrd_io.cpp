// NRRD reader and writer (http://teem.sourceforge.net/nrrd/format.html), written here rather than
// through teem: the parts of the format medical files use are small.
//
// Sections: [header] parsing the text header · [geometry] space, directions, origin, spacings ·
// [data] locating, decoding (raw, gzip) and converting the voxel data · [load] loadNrrd ·
// [write] writeNrrd.
#include "volume/nrrd_io.h"

#include <algorithm>
#include <bit>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <set>
#include <string>
#include <vector>

#include <zlib.h>

#include "core/strings.h"
#include "load_limits.h"
#include "core/printable_text.h"
#include "core/atomic_file.h"
#include "core/regular_file.h"
#include "gzip_bytes.h"
#include "raw_values.h"

namespace at {

namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// [header]

// The start of a NRRD file up to and including the blank line that ends its header (or the whole
// file when there is none), so that the memory check comes before attached data are read.
Result<std::string> readHeaderBytes(const RegularFile& file, const std::string& path) {
  constexpr std::size_t kChunk = 1 << 16, kMaxHeader = std::size_t(16) << 20;
  std::string bytes;
  std::size_t searched = 0;
  while (bytes.size() < kMaxHeader) {
    auto chunk = readFileRange(file, bytes.size(), kChunk, path);
    if (!chunk) return tl::unexpected(chunk.error());
    bytes += *chunk;
    if (bytes.size() >= 8 && bytes.compare(0, 7, "NRRD000") != 0)
      return fail(path + ": not a NRRD file (it does not start with NRRD0001…NRRD0005)");
    const std::size_t from = searched > 2 ? searched - 2 : 0;
    const std::size_t lf = bytes.find("\n\n", from), crlf = bytes.find("\n\r\n", from);
    if (lf != std::string::npos || crlf != std::string::npos) {
      const std::size_t end = std::min(lf == std::string::npos ? crlf + 3 : lf + 2,
                                       crlf == std::string::npos ? lf + 2 : crlf + 3);
      bytes.resize(end);
      return bytes;
    }
    searched = bytes.size();
    if (chunk->size() < kChunk) return bytes;  // end of file: a detached header
  }
  return fail(path + ": no end of the NRRD header within 16 MiB (a blank line must follow it)");
}

std::vector<std::string> splitWords(const std::string& s) {
  std::vector<std::string> words;
  std::istringstream in(s);
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

struct NrrdHeader {
  std::map<std::string, std::string> fields;     // "sizes" → "64 64 93"
  std::map<std::string, std::string> keyValues;  // "Segment0_Name" → "liver"
  std::vector<std::string> listFiles;            // file names after "data file: LIST"
  bool hasAttachedData = false;
  std::size_t dataOffset = 0;                    // start of attached data in the file
};

Result<NrrdHeader> parseHeader(const std::string& path, const std::string& bytes) {
  if (bytes.size() < 8 || bytes.compare(0, 7, "NRRD000") != 0 || bytes[7] < '1' || bytes[7] > '5')
    return fail(path + ": not a NRRD file (it does not start with NRRD0001…NRRD0005)");
  NrrdHeader header;
  std::size_t pos = bytes.find('\n');
  if (pos == std::string::npos) return fail(path + ": the NRRD header ends after its first line");
  ++pos;
  int lineNumber = 1;
  bool inList = false;
  while (pos < bytes.size()) {
    std::size_t end = bytes.find('\n', pos);
    const bool last = end == std::string::npos;
    if (last) end = bytes.size();
    std::string line = bytes.substr(pos, end - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = last ? bytes.size() : end + 1;
    ++lineNumber;
    if (line.empty()) {
      header.hasAttachedData = true;
      header.dataOffset = pos;
      break;
    }
    if (line[0] == '#') continue;
    if (inList) {
      header.listFiles.push_back(str::trim(line));
      continue;
    }
    const std::size_t field = line.find(": ");
    const std::size_t kv = line.find(":=");
    if (kv != std::string::npos && (field == std::string::npos || kv < field)) {
      header.keyValues[line.substr(0, kv)] = line.substr(kv + 2);
      continue;
    }
    if (field == std::string::npos)
      return fail(path + ": header line " + std::to_string(lineNumber) + " is not a \"field: value\" line");
    const std::string name = str::lower(str::trim(line.substr(0, field)));
    const std::string value = str::trim(line.substr(field + 2));
    header.fields[name] = value;
    if (name == "data file" || name == "datafile") {
      const auto words = splitWords(value);
      if (!words.empty() && words[0] == "LIST") inList = true;
    }
  }
  if (header.fields.count("datafile") && !header.fields.count("data file"))
    header.fields["data file"] = header.fields["datafile"];
  return header;
}

std::optional<ScalarKind> parseType(const std::string& text) {
  static const std::map<std::string, ScalarKind> kinds = {
      {"signed char", ScalarKind::Int8},     {"int8", ScalarKind::Int8},
      {"int8_t", ScalarKind::Int8},          {"uchar", ScalarKind::UInt8},
      {"unsigned char", ScalarKind::UInt8},  {"uint8", ScalarKind::UInt8},
      {"uint8_t", ScalarKind::UInt8},        {"short", ScalarKind::Int16},
      {"short int", ScalarKind::Int16},      {"signed short", ScalarKind::Int16},
      {"signed short int", ScalarKind::Int16}, {"int16", ScalarKind::Int16},
      {"int16_t", ScalarKind::Int16},        {"ushort", ScalarKind::UInt16},
      {"unsigned short", ScalarKind::UInt16}, {"unsigned short int", ScalarKind::UInt16},
      {"uint16", ScalarKind::UInt16},        {"uint16_t", ScalarKind::UInt16},
      {"int", ScalarKind::Int32},            {"signed int", ScalarKind::Int32},
      {"int32", ScalarKind::Int32},          {"int32_t", ScalarKind::Int32},
      {"uint", ScalarKind::UInt32},          {"unsigned int", ScalarKind::UInt32},
      {"uint32", ScalarKind::UInt32},        {"uint32_t", ScalarKind::UInt32},
      {"float", ScalarKind::Float32},        {"double", ScalarKind::Float64}};
  const auto it = kinds.find(text);
  if (it == kinds.end()) return std::nullopt;
  return it->second;
}

const char* nrrdTypeName(ScalarKind kind) {
  switch (kind) {
    case ScalarKind::Int8: return "int8";
    case ScalarKind::UInt8: return "uint8";
    case ScalarKind::Int16: return "short";
    case ScalarKind::UInt16: return "ushort";
    case ScalarKind::Int32: return "int";
    case ScalarKind::UInt32: return "uint";
    case ScalarKind::Float32: return "float";
    case ScalarKind::Float64: return "double";
  }
  return "short";
}

bool parseDouble(const std::string& text, double& out) {
  const std::string t = str::lower(text);
  if (t == "nan") {
    out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  char* end = nullptr;
  out = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0';
}

bool parseLong(const std::string& text, long long& out) {
  char* end = nullptr;
  out = std::strtoll(text.c_str(), &end, 10);
  return !text.empty() && end != text.c_str() && *end == '\0';
}

// "(a,b,c)" → vector.
bool parseVector(const std::string& text, Vec3& out) {
  if (text.size() < 2 || text.front() != '(' || text.back() != ')') return false;
  std::string inner = text.substr(1, text.size() - 2);
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = inner.find(',', start);
    parts.push_back(str::trim(inner.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (parts.size() != 3) return false;
  for (int a = 0; a < 3; ++a)
    if (!parseDouble(parts[std::size_t(a)], out[std::size_t(a)]) || !std::isfinite(out[std::size_t(a)])) return false;
  return true;
}

// Space directions are written "(a,b,c) (d,e,f) none"; vectors may hold spaces after commas.
std::vector<std::string> splitVectors(const std::string& value) {
  std::vector<std::string> out;
  std::size_t pos = 0;
  while (pos < value.size()) {
    while (pos < value.size() && std::isspace(static_cast<unsigned char>(value[pos]))) ++pos;
    if (pos >= value.size()) break;
    if (value[pos] == '(') {
      const std::size_t close = value.find(')', pos);
      if (close == std::string::npos) {
        out.push_back(value.substr(pos));
        break;
      }
      std::string v = value.substr(pos, close - pos + 1);
      v.erase(std::remove_if(v.begin(), v.end(), [](char c) { return std::isspace(static_cast<unsigned char>(c)); }),
              v.end());
      out.push_back(v);
      pos = close + 1;
    } else {
      std::size_t end = pos;
      while (end < value.size() && !std::isspace(static_cast<unsigned char>(value[end]))) ++end;
      out.push_back(value.substr(pos, end - pos));
      pos = end;
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// [geometry]

// Signs that take coordinates of the file's space to LPS. "3D-left-handed" has no anatomical
// meaning; it is read as left, posterior, inferior (z flipped makes a right-handed LPS frame), which
// is how the headsq sample matches its DICOM series (slice 1 of the NRRD is the top DICOM slice).
Result<Vec3> spaceToLps(const std::string& path, const std::string& space, std::vector<std::string>& notes) {
  const std::string s = str::lower(space);
  if (s == "left-posterior-superior" || s == "lps" || s == "3d-right-handed" || s == "scanner-xyz")
    return Vec3{1, 1, 1};
  if (s == "right-anterior-superior" || s == "ras") return Vec3{-1, -1, 1};
  if (s == "left-anterior-superior" || s == "las") return Vec3{1, -1, 1};
  if (s == "3d-left-handed") {
    notes.push_back("space 3D-left-handed read as left-posterior-inferior");
    return Vec3{1, 1, -1};
  }
  return fail(path + ": unsupported NRRD space '" + space +
              "' (supported: left-posterior-superior, right-anterior-superior, left-anterior-superior, "
              "3D-right-handed, 3D-left-handed, scanner-xyz)");
}

struct Layout {
  Dims dims;
  std::size_t valueCount = 0;   // all values in the file, including a size-1 non-spatial axis
  std::vector<int> spatialAxes; // the three axes of the grid among the file's axes
  int layerAxis = -1;           // a .seg.nrrd's list axis of several layers, or -1
  int layers = 1;
};

Result<Layout> parseLayout(const std::string& path, const NrrdHeader& h) {
  const auto dimIt = h.fields.find("dimension");
  if (dimIt == h.fields.end()) return fail(path + ": the NRRD header has no 'dimension' field");
  long long dimension = 0;
  if (!parseLong(dimIt->second, dimension) || dimension < 1)
    return fail(path + ": dimension '" + dimIt->second + "' is not a positive integer");
  if (dimension != 3 && dimension != 4)
    return fail(path + ": dimension " + std::to_string(dimension) + " is not supported (3, or 4 with one size-1 axis)");
  const auto sizesIt = h.fields.find("sizes");
  if (sizesIt == h.fields.end()) return fail(path + ": the NRRD header has no 'sizes' field");
  const auto words = splitWords(sizesIt->second);
  if (words.size() != std::size_t(dimension))
    return fail(path + ": 'sizes' lists " + std::to_string(words.size()) + " values but dimension is " +
                std::to_string(dimension));
  std::vector<long long> sizes;
  for (const auto& w : words) {
    long long v = 0;
    if (!parseLong(w, v) || v < 1 || v > std::numeric_limits<int>::max())
      return fail(path + ": size '" + w + "' is not a positive integer");
    sizes.push_back(v);
  }
  Layout layout;
  if (dimension == 3) {
    layout.spatialAxes = {0, 1, 2};
  } else {
    // The non-spatial axis: "none" in space directions, else a non-domain kind, else the first size-1 axis.
    // Only the first `dimension` entries describe axes (a header may list more; they are ignored).
    int other = -1;
    if (const auto it = h.fields.find("space directions"); it != h.fields.end()) {
      const auto vectors = splitVectors(it->second);
      for (std::size_t a = 0; a < vectors.size() && a < sizes.size(); ++a)
        if (vectors[a] == "none") other = int(a);
    }
    if (other < 0)
      if (const auto it = h.fields.find("kinds"); it != h.fields.end()) {
        const auto kinds = splitWords(it->second);
        for (std::size_t a = 0; a < kinds.size() && a < sizes.size(); ++a)
          if (kinds[a] != "domain" && kinds[a] != "space") other = int(a);
      }
    if (other < 0)
      for (int a = 0; a < 4 && other < 0; ++a)
        if (sizes[std::size_t(a)] == 1) other = a;
    if (other < 0) return fail(path + ": 4-dimensional NRRD without a non-spatial axis is not supported");
    // Several layers are a segmentation's (Slicer's .seg.nrrd with overlapping segments, its
    // Segment<N>_Layer keys say which layer holds a segment); other multi-component images are not
    // supported.
    if (sizes[std::size_t(other)] != 1) {
      if (h.keyValues.count("Segment0_Layer") == 0)
        return fail(path + ": axis " + std::to_string(other) + " holds " + std::to_string(sizes[std::size_t(other)]) +
                    " layers or components; only single-layer images and segmentations (.seg.nrrd) are supported");
      layout.layerAxis = other;
      layout.layers = int(sizes[std::size_t(other)]);
    }
    for (int a = 0; a < 4; ++a)
      if (a != other) layout.spatialAxes.push_back(a);
  }
  layout.dims = {int(sizes[std::size_t(layout.spatialAxes[0])]), int(sizes[std::size_t(layout.spatialAxes[1])]),
                 int(sizes[std::size_t(layout.spatialAxes[2])])};
  layout.valueCount = layout.dims.count() * std::size_t(layout.layers);
  return layout;
}

Result<Geometry> parseGeometry(const std::string& path, const NrrdHeader& h, const Layout& layout,
                               std::vector<std::string>& notes) {
  Vec3 toLps{1, 1, 1};
  const auto spaceIt = h.fields.find("space");
  if (spaceIt != h.fields.end()) {
    auto signs = spaceToLps(path, spaceIt->second, notes);
    if (!signs) return tl::unexpected(signs.error());
    toLps = *signs;
  } else if (const auto sd = h.fields.find("space dimension"); sd != h.fields.end() && str::trim(sd->second) != "3") {
    return fail(path + ": space dimension " + sd->second + " is not supported (3 only)");
  }

  Vec3 columns[3];
  if (const auto it = h.fields.find("space directions"); it != h.fields.end()) {
    const auto vectors = splitVectors(it->second);
    for (int c = 0; c < 3; ++c) {
      const std::size_t axis = std::size_t(layout.spatialAxes[std::size_t(c)]);
      if (axis >= vectors.size() || !parseVector(vectors[axis], columns[c]))
        return fail(path + ": 'space directions' has no valid vector for axis " + std::to_string(axis) + " ('" +
                    it->second + "')");
    }
  } else if (const auto sp = h.fields.find("spacings"); sp != h.fields.end()) {
    const auto words = splitWords(sp->second);
    for (int c = 0; c < 3; ++c) {
      const std::size_t axis = std::size_t(layout.spatialAxes[std::size_t(c)]);
      double s = 0;
      if (axis >= words.size() || !parseDouble(words[axis], s) || !std::isfinite(s))
        return fail(path + ": 'spacings' has no valid value for axis " + std::to_string(axis));
      if (s <= 0)
        return fail(path + ": spacing " + words[axis] + " of axis " + std::to_string(axis) + " is not positive");
      columns[c] = {0, 0, 0};
      columns[c][std::size_t(c)] = s;
    }
  } else {
    notes.push_back("no space directions or spacings: 1 mm voxels assumed");
    for (int c = 0; c < 3; ++c) {
      columns[c] = {0, 0, 0};
      columns[c][std::size_t(c)] = 1;
    }
  }

  Geometry g;
  g.dims = layout.dims;
  for (int c = 0; c < 3; ++c) {
    const Vec3 v{toLps[0] * columns[c][0], toLps[1] * columns[c][1], toLps[2] * columns[c][2]};
    const double length = norm(v);
    if (!(length > 1e-9)) return fail(path + ": axis " + std::to_string(c) + " has zero spacing");
    g.spacingMm[std::size_t(c)] = length;
    for (int r = 0; r < 3; ++r) g.direction.m[std::size_t(r)][std::size_t(c)] = v[std::size_t(r)] / length;
  }
  if (std::abs(g.direction.determinant()) < 1e-6)
    return fail(path + ": 'space directions' are parallel (the grid is degenerate)");
  if (const auto it = h.fields.find("space origin"); it != h.fields.end()) {
    Vec3 o;
    if (!parseVector(str::trim(it->second), o)) return fail(path + ": 'space origin' '" + it->second + "' is not (x,y,z)");
    g.originMm = {toLps[0] * o[0], toLps[1] * o[1], toLps[2] * o[2]};
  }
  return g;
}

// ---------------------------------------------------------------------------------------------
// [data]

// A "%d"-style format with exactly one integer conversion (flags 0, -, +, space and a width).
Result<std::string> formatFileName(const std::string& path, const std::string& format, long long n) {
  std::string out;
  bool converted = false;
  for (std::size_t i = 0; i < format.size(); ++i) {
    if (format[i] != '%') {
      out += format[i];
      continue;
    }
    if (i + 1 < format.size() && format[i + 1] == '%') {
      out += '%';
      ++i;
      continue;
    }
    std::size_t j = i + 1;
    bool zeroPad = false, left = false, plus = false;
    while (j < format.size() && std::strchr("0-+ ", format[j])) {
      zeroPad |= format[j] == '0';
      left |= format[j] == '-';
      plus |= format[j] == '+';
      ++j;
    }
    int width = 0;
    while (j < format.size() && std::isdigit(static_cast<unsigned char>(format[j])) && width < 100)
      width = width * 10 + (format[j++] - '0');
    if (j >= format.size() || !std::strchr("diu", format[j]) || converted)
      return fail(path + ": data file format '" + format + "' must hold exactly one %d conversion");
    converted = true;
    std::string digits = std::to_string(n < 0 ? -n : n);
    std::string sign = n < 0 ? "-" : (plus ? "+" : "");
    std::string number;
    const int pad = width - int(digits.size() + sign.size());
    if (pad > 0 && zeroPad && !left)
      number = sign + std::string(std::size_t(pad), '0') + digits;
    else if (pad > 0 && left)
      number = sign + digits + std::string(std::size_t(pad), ' ');
    else if (pad > 0)
      number = std::string(std::size_t(pad), ' ') + sign + digits;
    else
      number = sign + digits;
    out += number;
    i = j;
  }
  if (!converted) return fail(path + ": data file format '" + format + "' has no %d conversion");
  return out;
}

// The data files a header names, resolved against the header's folder; empty → attached data.
Result<std::vector<std::string>> dataFiles(const std::string& path, const NrrdHeader& h) {
  const auto it = h.fields.find("data file");
  if (it == h.fields.end()) return std::vector<std::string>{};
  const fs::path folder = fs::path(path).parent_path();
  auto resolve = [&](const std::string& name) {
    const fs::path p(name);
    return (p.is_absolute() ? p : folder / p).string();
  };
  const auto words = splitWords(it->second);
  if (words.empty()) return fail(path + ": 'data file' is empty");
  std::vector<std::string> files;
  if (words[0] == "LIST") {
    if (h.listFiles.empty()) return fail(path + ": 'data file: LIST' is followed by no file names");
    for (const auto& name : h.listFiles) files.push_back(resolve(name));
    return files;
  }
  long long first = 0, lastValue = 0, step = 0;
  if (words.size() >= 4 && words.size() <= 5 && parseLong(words[1], first) && parseLong(words[2], lastValue) &&
      parseLong(words[3], step)) {
    if (step == 0) return fail(path + ": 'data file' step is 0");
    constexpr long long kBound = 1000000000;
    if (std::llabs(first) > kBound || std::llabs(lastValue) > kBound || std::llabs(step) > kBound)
      return fail(path + ": 'data file' numbers " + words[1] + " " + words[2] + " " + words[3] + " are out of range");
    if ((lastValue - first) / step < 0)
      return fail(path + ": 'data file' range " + words[1] + ".." + words[2] + " with step " + words[3] + " is empty");
    const long long count = (lastValue - first) / step + 1;
    if (count > 1000000) return fail(path + ": 'data file' names " + std::to_string(count) + " files");
    for (long long n = first, i = 0; i < count; ++i, n += step) {
      auto name = formatFileName(path, words[0], n);
      if (!name) return tl::unexpected(name.error());
      files.push_back(resolve(*name));
    }
    return files;
  }
  files.push_back(resolve(it->second));
  return files;
}

// Converts decoded bytes to float voxels as they arrive, in pieces: values may straddle pieces
// and data files. `out` has its capacity reserved and grows only with values that exist.
class ValueSink {
 public:
  ValueSink(ScalarKind kind, std::size_t valueBytes, bool swap, std::vector<float>& out)
      : kind_(kind), valueBytes_(valueBytes), swap_(swap), out_(out), staging_(kStaging / valueBytes * valueBytes) {}

  void append(const unsigned char* data, std::size_t size) {
    while (size > 0) {
      const std::size_t n = std::min(size, staging_.size() - fill_);
      std::memcpy(staging_.data() + fill_, data, n);
      fill_ += n, data += n, size -= n;
      if (fill_ == staging_.size()) convert();
    }
  }
  // Converts what is left (a partial value cannot remain: the caller counts whole values).
  void finish() { convert(); }

  static constexpr std::size_t kStaging = std::size_t(1) << 20;

 private:
  void convert() {
    const std::size_t count = fill_ / valueBytes_;
    const std::size_t at = out_.size();
    out_.resize(at + count);
    detail::decodeRawValues(staging_.data(), count, kind_, swap_, out_.data() + at);
    const std::size_t rest = fill_ - count * valueBytes_;
    std::memmove(staging_.data(), staging_.data() + count * valueBytes_, rest);
    fill_ = rest;
  }

  ScalarKind kind_;
  std::size_t valueBytes_;
  bool swap_;
  std::vector<float>& out_;
  std::vector<unsigned char> staging_;
  std::size_t fill_ = 0;
};

struct InflateStream {
  z_stream zs{};
  bool ready = false;
  InflateStream() { ready = inflateInit2(&zs, 15 + 32) == Z_OK; }
  ~InflateStream() {
    if (ready) inflateEnd(&zs);
  }
  InflateStream(const InflateStream&) = delete;
  InflateStream& operator=(const InflateStream&) = delete;
};

struct Encoding {
  bool gzip = false;
  long long lineSkip = 0;
  long long byteSkip = 0;
};

// Bytes read from a file at a time (the raw read buffer and the inflate output buffer each).
constexpr std::size_t kReadPiece = std::size_t(1) << 20;

// Moves `pos` past `lines` lines of the file (NRRD's 'line skip', counted before decoding).
Status skipLines(const RegularFile& file, std::uint64_t& pos, long long lines, const std::string& what) {
  for (long long n = 0; n < lines;) {
    auto piece = readFileRange(file, pos, kReadPiece, what);
    if (!piece) return tl::unexpected(piece.error());
    if (piece->empty()) return fail(what + ": fewer lines than 'line skip' " + std::to_string(lines));
    std::size_t at = 0;
    while (n < lines) {
      const std::size_t nl = piece->find('\n', at);
      if (nl == std::string::npos) break;
      at = nl + 1;
      ++n;
    }
    pos += n < lines ? piece->size() : at;
  }
  return {};
}

// Raw data: exactly `need` bytes after `byteSkip` (or the last `need` bytes of the file when
// byteSkip is -1), read in pieces into `sink`. The file's size is checked before anything is read.
Status readRaw(const RegularFile& file, std::uint64_t pos, const Encoding& enc, std::size_t need,
               const std::string& sizeText, const std::string& what, ValueSink& sink,
               const ImageLoadOptions& options, const std::string& path) {
  const std::uint64_t available = file.sizeBytes > pos ? file.sizeBytes - pos : 0;
  if (enc.byteSkip == -1) {
    if (available < need) return fail(what + ": " + sizeText + " but the data holds " + std::to_string(available));
    pos = file.sizeBytes - need;
  } else {
    const auto skip = std::uint64_t(enc.byteSkip);
    const std::uint64_t holds = available > skip ? available - skip : 0;
    if (holds != need) return fail(what + ": " + sizeText + " but the data holds " + std::to_string(holds));
    pos += skip;
  }
  for (std::size_t done = 0; done < need;) {
    if (detail::loadCancelled(options)) return tl::unexpected(detail::cancelledError(path));
    auto piece = readFileRange(file, pos + done, std::min(kReadPiece, need - done), what);
    if (!piece) return tl::unexpected(piece.error());
    if (piece->empty()) return fail(what + ": the file became shorter while it was read");
    sink.append(reinterpret_cast<const unsigned char*>(piece->data()), piece->size());
    done += piece->size();
  }
  return {};
}

// Gzip (or zlib) data, possibly several members: `byteSkip` decompressed bytes are dropped, then
// exactly `need` bytes go to `sink`. Decompression stops one byte past `need`, so data that inflate
// to more than the header says (a gzip bomb) are refused after that byte, never inflated whole.
Status readGzip(const RegularFile& file, std::uint64_t pos, const Encoding& enc, std::size_t need,
                const std::string& sizeText, const std::string& what, ValueSink& sink,
                const ImageLoadOptions& options, const std::string& path) {
  if (enc.byteSkip < 0) return fail(what + ": 'byte skip: -1' is only allowed with raw encoding");
  InflateStream stream;
  if (!stream.ready) return fail(what + ": zlib could not start decompressing");
  z_stream& zs = stream.zs;
  const auto skip = std::uint64_t(enc.byteSkip);
  const std::uint64_t wanted = skip + need;  // decompressed bytes that matter
  std::uint64_t produced = 0;
  std::vector<unsigned char> output(kReadPiece);
  std::string input;
  bool inputEnded = false;
  bool streamEnded = false;
  while (true) {
    if (detail::loadCancelled(options)) return tl::unexpected(detail::cancelledError(path));
    if (zs.avail_in == 0 && !inputEnded) {
      auto piece = readFileRange(file, pos, kReadPiece, what);
      if (!piece) return tl::unexpected(piece.error());
      input = std::move(*piece);
      pos += input.size();
      inputEnded = input.size() < kReadPiece;
      zs.next_in = reinterpret_cast<Bytef*>(input.data());
      zs.avail_in = uInt(input.size());
    }
    if (streamEnded) {
      // Another gzip member may follow; anything else after the data is ignored, as gzip does.
      if (zs.avail_in == 0 && inputEnded) break;
      if (inflateReset(&zs) != Z_OK) return fail(what + ": zlib could not restart decompressing");
      streamEnded = false;
    }
    // Never ask for more than one byte beyond the data that matter.
    const std::uint64_t room = wanted + 1 - produced;
    zs.next_out = output.data();
    zs.avail_out = uInt(std::min<std::uint64_t>(output.size(), room));
    const uInt asked = zs.avail_out;
    const int rc = inflate(&zs, Z_NO_FLUSH);
    const std::size_t got = asked - zs.avail_out;
    // Hand over the part of this output that lies in [skip, skip + need).
    const std::uint64_t begin = std::max(produced, skip), end = std::min(produced + got, wanted);
    if (end > begin) sink.append(output.data() + (begin - produced), std::size_t(end - begin));
    produced += got;
    if (produced > wanted)
      return fail(what + ": " + sizeText + " but the decompressed data holds more");
    if (rc == Z_STREAM_END) {
      streamEnded = true;
      continue;
    }
    if (rc == Z_OK) continue;
    if (rc == Z_BUF_ERROR && zs.avail_in == 0 && inputEnded) break;  // input ended mid-stream
    if (rc == Z_BUF_ERROR) continue;
    return fail(what + ": the gzip data is corrupt (" + std::string(zs.msg ? zs.msg : "zlib error") + ")");
  }
  const std::uint64_t holds = produced > skip ? produced - skip : 0;
  if (!streamEnded)
    return fail(what + ": the gzip data ends early (the file is truncated) after " + std::to_string(holds) +
                " of the " + std::to_string(need) + " bytes of data");
  if (produced < wanted) return fail(what + ": " + sizeText + " but the decompressed data holds " + std::to_string(holds));
  return {};
}

std::vector<SegmentInfo> parseSegments(const NrrdHeader& h, std::vector<std::string>& notes) {
  std::vector<SegmentInfo> segments;
  for (int n = 0; n < 65536; ++n) {
    const std::string prefix = "Segment" + std::to_string(n) + "_";
    const auto name = h.keyValues.find(prefix + "Name");
    if (name == h.keyValues.end()) break;
    SegmentInfo s;
    s.name = str::trim(name->second);
    long long value = n + 1;
    if (const auto it = h.keyValues.find(prefix + "LabelValue"); it != h.keyValues.end()) {
      if (!parseLong(str::trim(it->second), value) || value < 0 || value > 65535) {
        notes.push_back("segment " + printableText(s.name, 60) + " has an invalid label value '" +
                        printableText(it->second, 20) + "'; skipped");
        continue;
      }
    }
    s.label = std::uint16_t(value);
    if (const auto it = h.keyValues.find(prefix + "Color"); it != h.keyValues.end()) {
      const auto words = splitWords(it->second);
      double c[3];
      if (words.size() == 3 && parseDouble(words[0], c[0]) && parseDouble(words[1], c[1]) && parseDouble(words[2], c[2]))
        s.colour = {float(c[0]), float(c[1]), float(c[2])};
    }
    segments.push_back(s);
  }
  return segments;
}

// A multi-layer segmentation (Slicer writes overlapping segments into layers, each segment a label
// value in one layer) as one label map: each segment keeps its label value where no other segment
// has it, else takes the next free value (noted); where segments of several layers overlap, the
// later layer wins (the count is noted). `loaded` holds all layers' values in file order and the
// segments as parseSegments read them; on return, one value per voxel and the segments' labels.
void mergeLayers(const NrrdHeader& h, const Layout& layout, LoadedImage& loaded) {
  struct Placed {
    std::size_t segment;
    int layer;
    long long value;
  };
  std::vector<Placed> placed;
  std::set<std::uint16_t> taken;
  std::uint16_t next = 1;
  for (std::size_t k = 0; k < loaded.segments.size(); ++k) {
    long long layer = 0;
    for (int n = 0; n < 65536; ++n) {  // the segment's key index: the n whose name and value match
      const std::string prefix = "Segment" + std::to_string(n) + "_";
      const auto name = h.keyValues.find(prefix + "Name");
      if (name == h.keyValues.end()) break;
      long long value = n + 1;
      if (const auto it = h.keyValues.find(prefix + "LabelValue"); it != h.keyValues.end()) parseLong(str::trim(it->second), value);
      if (str::trim(name->second) != loaded.segments[k].name || value != loaded.segments[k].label) continue;
      if (const auto it = h.keyValues.find(prefix + "Layer"); it != h.keyValues.end()) parseLong(str::trim(it->second), layer);
      break;
    }
    placed.push_back({k, int(layer), loaded.segments[k].label});
  }
  std::vector<std::map<long long, std::uint16_t>> lookup(std::size_t(layout.layers));
  for (Placed& p : placed) {
    std::uint16_t out = std::uint16_t(p.value);
    if (taken.count(out)) {
      while (taken.count(next)) ++next;
      loaded.notes.push_back("segment " + loaded.segments[p.segment].name + " (layer " + std::to_string(p.layer) +
                             ", value " + std::to_string(p.value) + ") became label " + std::to_string(next) +
                             ": its value is another layer's");
      out = next;
    }
    taken.insert(out);
    loaded.segments[p.segment].label = out;
    if (p.layer >= 0 && p.layer < layout.layers) lookup[std::size_t(p.layer)][p.value] = out;
  }
  // File strides: axis a advances by the product of the earlier axes' sizes.
  std::size_t stride[4] = {1, 1, 1, 1};
  std::size_t size[4];
  for (int a = 0, s = 0; a < 4; ++a) {
    if (a == layout.layerAxis) {
      size[a] = std::size_t(layout.layers);
    } else {
      const int spatial = s++;
      size[a] = std::size_t(spatial == 0 ? layout.dims.x : spatial == 1 ? layout.dims.y : layout.dims.z);
    }
  }
  for (int a = 1; a < 4; ++a) stride[a] = stride[a - 1] * size[a - 1];
  const std::size_t layerStride = stride[layout.layerAxis];
  const std::size_t sx = stride[layout.spatialAxes[0]], sy = stride[layout.spatialAxes[1]], sz = stride[layout.spatialAxes[2]];
  const Dims d = layout.dims;
  std::vector<float> merged(d.count(), 0.0f);
  std::size_t overlaps = 0;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const std::size_t base = std::size_t(i) * sx + std::size_t(j) * sy + std::size_t(k) * sz;
        float& out = merged[d.index(i, j, k)];
        for (int layer = 0; layer < layout.layers; ++layer) {
          const float v = loaded.image.voxels[base + std::size_t(layer) * layerStride];
          if (v == 0) continue;
          const auto it = lookup[std::size_t(layer)].find((long long)(v));
          if (it == lookup[std::size_t(layer)].end()) continue;  // a value no segment names
          overlaps += out != 0;
          out = float(it->second);
        }
      }
  loaded.image.voxels = std::move(merged);
  loaded.notes.push_back("merged " + std::to_string(layout.layers) + " segmentation layers into one label map" +
                         (overlaps ? " (" + std::to_string(overlaps) + " voxels in several segments: the later layer's)" : ""));
}

// Checks that a data file lies in the folder its header may read from: the header's own folder, or
// the one the user named (ImageLoadOptions::dataFolder). Symbolic links are resolved first, so a
// link inside the folder cannot lead out of it.
Status checkDataFileConfined(const std::string& path, const std::string& file, const ImageLoadOptions& options) {
  std::error_code ec;
  fs::path allowed = fs::weakly_canonical(
      options.dataFolder.empty() ? fs::absolute(fs::path(path), ec).parent_path() : fs::path(options.dataFolder), ec);
  const fs::path resolved = fs::weakly_canonical(fs::absolute(fs::path(file), ec), ec);
  if (!allowed.empty() && allowed.filename().empty()) allowed = allowed.parent_path();  // "dir/" → "dir"
  if (ec) return fail(path + ": data file " + file + " cannot be resolved (" + ec.message() + ")");
  const auto mismatch = std::mismatch(allowed.begin(), allowed.end(), resolved.begin(), resolved.end());
  if (mismatch.first == allowed.end() && resolved != allowed) return {};
  return fail(path + ": data file " + file + " lies outside " +
              (options.dataFolder.empty() ? "the header's folder " + allowed.string() +
                                                " (name a folder that may be read with --nrrd-data DIR)"
                                          : "the folder allowed for data files, " + allowed.string()));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// [load]

namespace {

Result<LoadedImage> readNrrd(const std::string& path, const ImageLoadOptions& options) {
  auto headerFile = openRegularFile(path, path);
  if (!headerFile) return tl::unexpected(headerFile.error());
  auto headerBytes = readHeaderBytes(*headerFile, path);
  if (!headerBytes) return tl::unexpected(headerBytes.error());
  auto header = parseHeader(path, *headerBytes);
  if (!header) return tl::unexpected(header.error());
  const NrrdHeader& h = *header;

  const auto typeIt = h.fields.find("type");
  if (typeIt == h.fields.end()) return fail(path + ": the NRRD header has no 'type' field");
  const auto kind = parseType(typeIt->second);
  if (!kind)
    return fail(path + ": unsupported NRRD type '" + typeIt->second +
                "' (supported: int8, uint8, int16, uint16, int32, uint32, float, double)");

  Encoding enc;
  const auto encIt = h.fields.find("encoding");
  if (encIt == h.fields.end()) return fail(path + ": the NRRD header has no 'encoding' field");
  const std::string encoding = str::lower(encIt->second);
  if (encoding == "gzip" || encoding == "gz")
    enc.gzip = true;
  else if (encoding != "raw")
    return fail(path + ": unsupported NRRD encoding '" + encIt->second + "' (supported: raw, gzip)");
  if (const auto it = h.fields.find("line skip"); it != h.fields.end())
    if (!parseLong(it->second, enc.lineSkip) || enc.lineSkip < 0)
      return fail(path + ": 'line skip' '" + it->second + "' is not a non-negative integer");
  if (const auto it = h.fields.find("byte skip"); it != h.fields.end())
    if (!parseLong(it->second, enc.byteSkip) || enc.byteSkip < -1)
      return fail(path + ": 'byte skip' '" + it->second + "' is not -1 or a non-negative integer");

  bool swap = false;
  if (detail::bytesOf(*kind) > 1) {
    const auto endianIt = h.fields.find("endian");
    if (endianIt == h.fields.end()) return fail(path + ": the NRRD header has no 'endian' field for multi-byte data");
    const std::string endian = str::lower(endianIt->second);
    if (endian != "little" && endian != "big")
      return fail(path + ": 'endian' is '" + endianIt->second + "', not little or big");
    swap = endian == "big";
  }

  LoadedImage loaded;
  loaded.storedKind = *kind;
  auto layout = parseLayout(path, h);
  if (!layout) return tl::unexpected(layout.error());
  auto geometry = parseGeometry(path, h, *layout, loaded.notes);
  if (!geometry) return tl::unexpected(geometry.error());
  // Transient buffers: the raw read piece, the inflate output piece and the conversion staging.
  const double transient = double(kReadPiece) * 2 + double(ValueSink::kStaging);
  if (auto fits = detail::checkImageFits(path, layout->dims, transient, options); !fits)
    return tl::unexpected(fits.error());

  auto files = dataFiles(path, h);
  if (!files) return tl::unexpected(files.error());
  for (const std::string& file : *files)
    if (auto inside = checkDataFileConfined(path, file, options); !inside) return tl::unexpected(inside.error());
  const std::size_t valueBytes = detail::bytesOf(*kind);
  const std::size_t totalBytes = layout->valueCount * valueBytes;
  const std::string typeText = std::string(toString(*kind));
  loaded.image.geometry = *geometry;
  std::vector<float>& out = loaded.image.voxels;
  // Address space for the whole image; pages are only touched as decoded values arrive.
  out.reserve(layout->valueCount);
  ValueSink sink(*kind, valueBytes, swap, out);
  const auto readData = [&](const RegularFile& file, std::uint64_t pos, std::size_t need, const std::string& sizeText,
                            const std::string& what) -> Status {
    if (auto ok = skipLines(file, pos, enc.lineSkip, what); !ok) return ok;
    return enc.gzip ? readGzip(file, pos, enc, need, sizeText, what, sink, options, path)
                    : readRaw(file, pos, enc, need, sizeText, what, sink, options, path);
  };
  if (files->empty()) {
    if (!h.hasAttachedData) return fail(path + ": the NRRD header names no data file and holds no data");
    const std::string sizeText =
        "dimensions " + layout->dims.toString() + " × " + typeText + " need " + std::to_string(totalBytes) + " bytes";
    if (auto ok = readData(*headerFile, h.dataOffset, totalBytes, sizeText, path); !ok) return tl::unexpected(ok.error());
  } else {
    const std::size_t n = files->size();
    if (totalBytes % n != 0)
      return fail(path + ": " + std::to_string(totalBytes) + " bytes of data cannot be split evenly over " +
                  std::to_string(n) + " data files");
    const std::size_t perFile = totalBytes / n;
    const std::string sizeText = "each of the " + std::to_string(n) + " data files of " + layout->dims.toString() +
                                 " × " + typeText + " needs " + std::to_string(perFile) + " bytes";
    if (options.progress) options.progress(0, n);
    for (std::size_t i = 0; i < n; ++i) {
      if (detail::loadCancelled(options)) return tl::unexpected(detail::cancelledError(path));
      const std::string& name = (*files)[i];
      const std::string what = path + ": data file " + name;
      auto dataFile = openRegularFile(name, what);
      if (!dataFile) return tl::unexpected(dataFile.error());
      if (auto ok = readData(*dataFile, 0, perFile, sizeText, what); !ok) return tl::unexpected(ok.error());
      if (options.progress) options.progress(i + 1, n);
    }
    if (n > 1) loaded.notes.push_back("read " + std::to_string(n) + " data files");
  }
  sink.finish();
  if (out.size() != layout->valueCount)
    return fail(path + ": decoded " + std::to_string(out.size()) + " values but the header describes " +
                std::to_string(layout->valueCount));
  loaded.segments = parseSegments(h, loaded.notes);
  if (layout->layers > 1) mergeLayers(h, *layout, loaded);
  return loaded;
}

}  // namespace

Result<LoadedImage> loadNrrd(const std::string& path, const ImageLoadOptions& options) {
  return withPrintableError(readNrrd(path, options));
}

// ---------------------------------------------------------------------------------------------
// [write]

namespace {

template <class T>
Status packValues(const std::string& path, const std::vector<float>& values, const Dims& dims, std::string& out) {
  out.resize(values.size() * sizeof(T));
  for (std::size_t n = 0; n < values.size(); ++n) {
    const float v = values[n];
    T stored;
    if constexpr (std::is_floating_point_v<T>) {
      stored = T(v);
    } else {
      if (!std::isfinite(v) || v != std::floor(v) || double(v) < double(std::numeric_limits<T>::lowest()) ||
          double(v) > double(std::numeric_limits<T>::max())) {
        const std::size_t i = n % std::size_t(dims.x), j = (n / std::size_t(dims.x)) % std::size_t(dims.y),
                          k = n / (std::size_t(dims.x) * std::size_t(dims.y));
        std::ostringstream s;
        s << v;
        return fail(path + ": voxel (" + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) +
                    ") value " + s.str() + " cannot be stored as the requested integer type");
      }
      stored = T(v);
    }
    std::memcpy(out.data() + n * sizeof(T), &stored, sizeof(T));
  }
  return {};
}

std::string numberText(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.17g", v == 0 ? 0.0 : v);  // no "-0"
  return buffer;
}

}  // namespace

Status writeNrrd(const std::string& path, const FloatVolume& image, ScalarKind storedKind,
                 const std::vector<std::pair<std::string, std::string>>& keyValues) {
  if (auto ok = checkOutputPath(path, path); !ok) return ok;
  const Geometry& g = image.geometry;
  if (g.dims.count() == 0 || image.voxels.size() != g.dims.count()) return fail(path + ": image to write is empty");
  static_assert(std::endian::native == std::endian::little, "writeNrrd writes native byte order as little endian");
  std::string plain;
  Status packed;
  switch (storedKind) {
    case ScalarKind::Int8: packed = packValues<std::int8_t>(path, image.voxels, g.dims, plain); break;
    case ScalarKind::UInt8: packed = packValues<std::uint8_t>(path, image.voxels, g.dims, plain); break;
    case ScalarKind::Int16: packed = packValues<std::int16_t>(path, image.voxels, g.dims, plain); break;
    case ScalarKind::UInt16: packed = packValues<std::uint16_t>(path, image.voxels, g.dims, plain); break;
    case ScalarKind::Int32: packed = packValues<std::int32_t>(path, image.voxels, g.dims, plain); break;
    case ScalarKind::UInt32: packed = packValues<std::uint32_t>(path, image.voxels, g.dims, plain); break;
    case ScalarKind::Float32: packed = packValues<float>(path, image.voxels, g.dims, plain); break;
    case ScalarKind::Float64: packed = packValues<double>(path, image.voxels, g.dims, plain); break;
  }
  if (!packed) return packed;
  auto compressed = gzipBytes(path, plain);
  if (!compressed) return tl::unexpected(compressed.error());

  std::ostringstream header;
  header << "NRRD0004\n";
  header << "type: " << nrrdTypeName(storedKind) << "\n";
  header << "dimension: 3\n";
  header << "space: left-posterior-superior\n";
  header << "sizes: " << g.dims.x << " " << g.dims.y << " " << g.dims.z << "\n";
  header << "space directions:";
  for (int c = 0; c < 3; ++c) {
    header << " (";
    for (int r = 0; r < 3; ++r)
      header << (r ? "," : "") << numberText(g.direction.m[std::size_t(r)][std::size_t(c)] * g.spacingMm[std::size_t(c)]);
    header << ")";
  }
  header << "\nkinds: domain domain domain\n";
  header << "endian: little\n";
  header << "encoding: gzip\n";
  header << "space origin: (" << numberText(g.originMm[0]) << "," << numberText(g.originMm[1]) << ","
         << numberText(g.originMm[2]) << ")\n";
  for (const auto& [key, value] : keyValues) {
    if (key.find(":=") != std::string::npos || key.find('\n') != std::string::npos || value.find('\n') != std::string::npos)
      return fail(path + ": NRRD key '" + key + "' or its value holds ':=' or a line break");
    header << key << ":=" << value << "\n";
  }
  header << "\n";

  auto out = AtomicFile::create(path);
  if (!out) return tl::unexpected(out.error());
  if (auto ok = out->write(header.str()); !ok) return ok;
  if (auto ok = out->write(*compressed); !ok) return ok;
  return out->commit();
}

namespace {

// The header of the NRRD at `path`; none for a file that is not a NRRD.
Result<std::optional<NrrdHeader>> headerOf(const std::string& path) {
  auto headerFile = openRegularFile(path, path);
  if (!headerFile) return tl::unexpected(headerFile.error());
  auto magic = readFileRange(*headerFile, 0, 8, path);
  if (!magic) return tl::unexpected(magic.error());
  if (magic->size() < 8 || magic->compare(0, 7, "NRRD000") != 0) return std::optional<NrrdHeader>{};
  auto headerBytes = readHeaderBytes(*headerFile, path);
  if (!headerBytes) return tl::unexpected(headerBytes.error());
  auto header = parseHeader(path, *headerBytes);
  if (!header) return tl::unexpected(header.error());
  return std::optional<NrrdHeader>(std::move(*header));
}

Result<std::vector<std::string>> listDataFiles(const std::string& path, const ImageLoadOptions& options) {
  auto header = headerOf(path);
  if (!header) return tl::unexpected(header.error());
  if (!*header) return std::vector<std::string>{};
  auto files = dataFiles(path, **header);
  if (!files) return tl::unexpected(files.error());
  for (const std::string& file : *files)
    if (auto inside = checkDataFileConfined(path, file, options); !inside) return tl::unexpected(inside.error());
  return files;
}

}  // namespace

Result<std::vector<std::string>> nrrdDataFiles(const std::string& path, const ImageLoadOptions& options) {
  return withPrintableError(listDataFiles(path, options));
}

Result<bool> nrrdDataFilesRelativeToHeader(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) return true;  // a DICOM series
  auto header = headerOf(path);
  if (!header) return withPrintableError(Result<bool>(tl::unexpected(header.error())));
  if (!*header) return true;
  // Resolved against no folder, each name stays as the header writes it.
  auto names = dataFiles(fs::path(path).filename().string(), **header);
  if (!names) return withPrintableError(Result<bool>(tl::unexpected(names.error())));
  for (const std::string& name : *names) {
    const fs::path p(name);
    if (p.is_absolute() || std::any_of(p.begin(), p.end(), [](const fs::path& part) { return part == ".."; })) return false;
  }
  return true;
}

}  // namespace at
