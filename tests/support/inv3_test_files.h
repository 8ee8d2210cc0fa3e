// Helpers for the InVesalius loader tests: a main.plist written from fields (so that tests control
// every field, including broken ones), raw int16 matrices, and tar archives written with
// libarchive, gzip-compressed (as InVesalius does by default) or plain.
#pragma once

#include <archive.h>
#include <archive_entry.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace at::test {

// main.plist's fields as XML plist fragments (the value element, e.g. "<integer>1</integer>").
// Setting a field to "" leaves it out.
struct Inv3Plist {
  std::map<std::string, std::string> top = {
      {"format_version", "<integer>1</integer>"},
      {"modality", "<string>CT</string>"},
      {"name", "<string>Test Patient</string>"},
      {"orientation", "<integer>1</integer>"},
      {"spacing", "<array><real>0.5</real><real>0.75</real><real>2.0</real></array>"},
  };
  std::map<std::string, std::string> matrix = {
      {"dtype", "<string>int16</string>"},
      {"filename", "<string>matrix.dat</string>"},
      {"shape", "<array><integer>3</integer><integer>5</integer><integer>7</integer></array>"},
  };
  bool withMatrix = true;  // false: no 'matrix' dictionary at all

  std::string xml() const {
    std::string s =
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        "<!DOCTYPE plist PUBLIC \"-//Apple Computer//DTD PLIST 1.0//EN\" \"http://www.apple.com/DTDs/PropertyList-1.0.dtd\">\n"
        "<plist version=\"1.0\">\n<dict>\n";
    for (const auto& [key, value] : top)
      if (!value.empty()) s += "\t<key>" + key + "</key>\n\t" + value + "\n";
    if (withMatrix) {
      s += "\t<key>matrix</key>\n\t<dict>\n";
      for (const auto& [key, value] : matrix)
        if (!value.empty()) s += "\t\t<key>" + key + "</key>\n\t\t" + value + "\n";
      s += "\t</dict>\n";
    }
    s += "</dict>\n</plist>\n";
    return s;
  }
};

// The shape of Inv3Plist's default matrix: 3 slices (z) of 5 rows (y) of 7 columns (x).
constexpr int kInv3X = 7, kInv3Y = 5, kInv3Z = 3;

// A value for voxel (x, y, z) that differs at every voxel and spans negative HU.
inline std::int16_t inv3TestValue(int x, int y, int z) { return std::int16_t(-1000 + 100 * z + 10 * y + x); }

// Little-endian int16 bytes in numpy's C order (z slowest, x fastest).
inline std::string inv3Matrix(int nx = kInv3X, int ny = kInv3Y, int nz = kInv3Z) {
  std::string bytes;
  for (int z = 0; z < nz; ++z)
    for (int y = 0; y < ny; ++y)
      for (int x = 0; x < nx; ++x) {
        const std::uint16_t v = std::uint16_t(inv3TestValue(x, y, z));
        bytes.push_back(char(v & 0xff));
        bytes.push_back(char(v >> 8));
      }
  return bytes;
}

struct TarMember {
  std::string name;   // path inside the archive, e.g. "tmpabc/main.plist"
  std::string bytes;
};

// Writes `members` in order as a tar archive, gzip-compressed unless `gzip` is false.
inline void writeTar(const std::filesystem::path& path, const std::vector<TarMember>& members, bool gzip = true) {
  struct WriteFree {
    void operator()(archive* a) const { archive_write_free(a); }
  };
  std::unique_ptr<archive, WriteFree> writer(archive_write_new());
  archive_write_set_format_pax_restricted(writer.get());
  if (gzip) archive_write_add_filter_gzip(writer.get());
  else archive_write_add_filter_none(writer.get());
  if (archive_write_open_filename(writer.get(), path.c_str()) != ARCHIVE_OK)
    throw std::runtime_error("writeTar: cannot create " + path.string());
  for (const TarMember& m : members) {
    std::unique_ptr<archive_entry, void (*)(archive_entry*)> entry(archive_entry_new(), archive_entry_free);
    archive_entry_set_pathname(entry.get(), m.name.c_str());
    archive_entry_set_filetype(entry.get(), AE_IFREG);
    archive_entry_set_perm(entry.get(), 0644);
    archive_entry_set_size(entry.get(), la_int64_t(m.bytes.size()));
    archive_write_header(writer.get(), entry.get());
    if (!m.bytes.empty()) archive_write_data(writer.get(), m.bytes.data(), m.bytes.size());
  }
  archive_write_close(writer.get());
}

// A valid project: main.plist and the matrix in folder `folder/`, in that order.
inline void writeInv3(const std::filesystem::path& path, const Inv3Plist& plist = {},
                      const std::string& matrix = inv3Matrix(), const std::string& folder = "tmpproject") {
  writeTar(path, {{folder + "/main.plist", plist.xml()}, {folder + "/matrix.dat", matrix}});
}

// Property lists nested `depth` levels (the stack-overflow inputs of libplist).
// A main.plist whose 'matrix' holds `depth` nested arrays.
inline std::string deepXmlPlist(int depth) {
  std::string s = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<plist version=\"1.0\">\n<dict><key>matrix</key>";
  s.reserve(s.size() + std::size_t(depth) * 15);
  for (int i = 0; i < depth; ++i) s += "<array>";
  for (int i = 0; i < depth; ++i) s += "</array>";
  return s + "</dict>\n</plist>\n";
}

// A binary plist ("bplist00") of `depth` arrays, each holding the next (the last one holding the
// first when `cycle`).
inline std::string deepBinaryPlist(std::uint32_t depth, bool cycle = false) {
  std::string s = "bplist00";
  std::vector<std::uint32_t> offsets;
  const auto be32 = [&](std::uint32_t v) {
    for (int b = 3; b >= 0; --b) s.push_back(char((v >> (8 * b)) & 0xff));
  };
  for (std::uint32_t i = 0; i < depth; ++i) {
    offsets.push_back(std::uint32_t(s.size()));
    if (i + 1 < depth || cycle) {
      s.push_back(char(0xA1));
      be32(i + 1 < depth ? i + 1 : 0);
    } else {
      s.push_back(char(0xA0));
    }
  }
  const std::uint64_t table = s.size();
  for (std::uint32_t o : offsets) be32(o);
  std::string trailer(32, '\0');
  trailer[6] = 4;
  trailer[7] = 4;
  for (int b = 0; b < 8; ++b) {
    trailer[std::size_t(8 + b)] = char((std::uint64_t(depth) >> (8 * (7 - b))) & 0xff);
    trailer[std::size_t(24 + b)] = char((table >> (8 * (7 - b))) & 0xff);
  }
  return s + trailer;
}

}  // namespace at::test
