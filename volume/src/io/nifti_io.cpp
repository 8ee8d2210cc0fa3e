// NIfTI-1/NIfTI-2 through niftilib (libnifti2 reads both). The file itself is read here through
// zlib (which reads plain and gzip files alike) and niftilib interprets the header
// (nifti_convert_n{1,2}hdr2nim: byte order, qform/sform). Two reasons: niftilib reports problems only
// on stderr, and its file-name resolution opens "x.nii" when asked for "x.nii.gz" if both exist.
#include "volume/nifti_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>

#include <nifti2_io.h>
#include <zlib.h>

#include "core/strings.h"
#include "load_limits.h"
#include "core/printable_text.h"
#include "core/atomic_file.h"
#include "core/regular_file.h"
#include "gzip_bytes.h"

namespace at {

namespace {

namespace fs = std::filesystem;

struct NiftiImageDeleter {
  void operator()(nifti_image* image) const { nifti_image_free(image); }
};
using NiftiImagePtr = std::unique_ptr<nifti_image, NiftiImageDeleter>;

struct GzFileCloser {
  void operator()(gzFile_s* file) const { gzclose(file); }
};
using GzFilePtr = std::unique_ptr<gzFile_s, GzFileCloser>;

// Quiet niftilib: its messages go to stderr; ours travel as values.
void quietNiftilib() {
  static const bool once = [] {
    nifti_set_debug_level(0);
    return true;
  }();
  (void)once;
}

std::uint32_t readU32(const unsigned char* p, bool swap) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  if (swap) v = __builtin_bswap32(v);
  return v;
}

std::string gzMessage(gzFile_s* file) {
  int code = 0;
  const char* message = gzerror(file, &code);
  return message && *message ? message : "zlib error";
}

// Reads exactly `size` bytes; returns how many were read, or -1 on a zlib error.
long long gzReadFully(gzFile_s* file, void* buffer, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const unsigned chunk = unsigned(std::min<std::size_t>(size - done, std::size_t(1) << 30));
    const int got = gzread(file, static_cast<char*>(buffer) + done, chunk);
    if (got < 0) return -1;
    if (got == 0) break;
    done += std::size_t(got);
  }
  return (long long)done;
}

bool kindOf(int datatype, ScalarKind& kind);

std::uint16_t readU16(const unsigned char* p, bool swap) {
  std::uint16_t v;
  std::memcpy(&v, p, 2);
  if (swap) v = std::uint16_t((v >> 8) | (v << 8));
  return v;
}

std::int64_t readI64(const unsigned char* p, bool swap) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  if (swap) v = __builtin_bswap64(v);
  return std::int64_t(v);
}

// Checks dim[] and datatype before niftilib sees them (it prints to stderr about bad values).
Status checkDimsAndType(const std::string& path, const std::int64_t dim[8], int datatype) {
  if (dim[0] < 1 || dim[0] > 7) return fail(path + ": dim[0] is " + std::to_string(dim[0]) + ", not 1..7");
  for (int d = 1; d <= dim[0]; ++d)
    if (dim[d] < 1) return fail(path + ": dim[" + std::to_string(d) + "] is " + std::to_string(dim[d]) + ", not positive");
  ScalarKind kind;
  if (!kindOf(datatype, kind))
    return fail(path + ": unsupported NIfTI datatype " + std::string(nifti_datatype_string(datatype)) + " (code " +
                std::to_string(datatype) + "; supported: int8, uint8, int16, uint16, int32, uint32, float32, float64)");
  return {};
}

struct NiftiHeader {
  NiftiImagePtr nim;
  double pixdim[3] = {0, 0, 0};  // as stored: niftilib replaces zero pixdims with 1
};

// Reads and checks the header of the (possibly gzip-compressed) file and lets niftilib convert it.
Result<NiftiHeader> readNiftiHeader(const std::string& path, gzFile_s* file) {
  unsigned char header[540] = {};
  const long long got = gzReadFully(file, header, sizeof header);
  if (got < 0) return fail(path + ": the compressed data is corrupt (" + gzMessage(file) + ")");
  if (got < 348)
    return fail(path + ": file holds " + std::to_string(got) + " bytes, too short for a NIfTI header (348 bytes)");
  const std::uint32_t size = readU32(header, false);
  const std::uint32_t swapped = readU32(header, true);
  nifti_image* nim = nullptr;
  NiftiHeader result;
  const bool swap = size != 348 && size != 540;
  if (size == 348 || swapped == 348) {
    for (int a = 0; a < 3; ++a) {
      std::uint32_t bits = readU32(header + 80 + 4 * a, swap);
      float value;
      std::memcpy(&value, &bits, 4);
      result.pixdim[a] = value;
    }
    if (std::memcmp(header + 344, "n+1\0", 4) != 0)
      return fail(path + ": not a single-file NIfTI-1 image (magic at byte 344 is not \"n+1\")");
    std::int64_t dim[8];
    for (int d = 0; d < 8; ++d) dim[d] = std::int16_t(readU16(header + 40 + 2 * d, swap));
    if (auto ok = checkDimsAndType(path, dim, std::int16_t(readU16(header + 70, swap))); !ok)
      return tl::unexpected(ok.error());
    nifti_1_header h;
    std::memcpy(&h, header, sizeof h);
    nim = nifti_convert_n1hdr2nim(h, path.c_str());
  } else if (size == 540 || swapped == 540) {
    if (got < 540) return fail(path + ": file holds " + std::to_string(got) + " bytes, too short for a NIfTI-2 header");
    if (std::memcmp(header + 4, "n+2\0", 4) != 0)
      return fail(path + ": not a single-file NIfTI-2 image (magic at byte 4 is not \"n+2\")");
    for (int a = 0; a < 3; ++a) {
      std::uint64_t bits;
      std::memcpy(&bits, header + 112 + 8 * a, 8);
      if (swap) bits = __builtin_bswap64(bits);
      std::memcpy(&result.pixdim[a], &bits, 8);
    }
    std::int64_t dim[8];
    for (int d = 0; d < 8; ++d) dim[d] = readI64(header + 16 + 8 * d, swap);
    if (auto ok = checkDimsAndType(path, dim, std::int16_t(readU16(header + 12, swap))); !ok)
      return tl::unexpected(ok.error());
    nifti_2_header h;
    std::memcpy(&h, header, sizeof h);
    nim = nifti_convert_n2hdr2nim(h, path.c_str());
  } else {
    return fail(path + ": not a NIfTI file (header size field is " + std::to_string(size) + ", not 348 or 540)");
  }
  if (!nim) return fail(path + ": niftilib cannot interpret the NIfTI header (inconsistent fields)");
  result.nim.reset(nim);
  return result;
}

bool kindOf(int datatype, ScalarKind& kind) {
  switch (datatype) {
    case DT_INT8: kind = ScalarKind::Int8; return true;
    case DT_UINT8: kind = ScalarKind::UInt8; return true;
    case DT_INT16: kind = ScalarKind::Int16; return true;
    case DT_UINT16: kind = ScalarKind::UInt16; return true;
    case DT_INT32: kind = ScalarKind::Int32; return true;
    case DT_UINT32: kind = ScalarKind::UInt32; return true;
    case DT_FLOAT32: kind = ScalarKind::Float32; return true;
    case DT_FLOAT64: kind = ScalarKind::Float64; return true;
    default: return false;
  }
}

// Converts `count` stored values (native byte order; they may be unaligned in `data`) to floats.
template <class T>
void convertVoxels(const unsigned char* data, float* out, std::size_t count, double slope, double inter) {
  for (std::size_t n = 0; n < count; ++n) {
    T v;
    std::memcpy(&v, data + n * sizeof(T), sizeof(T));
    out[n] = slope == 1.0 && inter == 0.0 ? float(v) : float(double(v) * slope + inter);
  }
}

void convertPiece(ScalarKind kind, const unsigned char* data, float* out, std::size_t count, double slope,
                  double inter) {
  switch (kind) {
    case ScalarKind::Int8: convertVoxels<std::int8_t>(data, out, count, slope, inter); break;
    case ScalarKind::UInt8: convertVoxels<std::uint8_t>(data, out, count, slope, inter); break;
    case ScalarKind::Int16: convertVoxels<std::int16_t>(data, out, count, slope, inter); break;
    case ScalarKind::UInt16: convertVoxels<std::uint16_t>(data, out, count, slope, inter); break;
    case ScalarKind::Int32: convertVoxels<std::int32_t>(data, out, count, slope, inter); break;
    case ScalarKind::UInt32: convertVoxels<std::uint32_t>(data, out, count, slope, inter); break;
    case ScalarKind::Float32: convertVoxels<float>(data, out, count, slope, inter); break;
    case ScalarKind::Float64: convertVoxels<double>(data, out, count, slope, inter); break;
  }
}

// NIfTI's world is RAS+; ours is LPS: negate the first two rows of the affine.
Result<Geometry> geometryFromAffine(const std::string& path, const nifti_dmat44& ras, const Dims& dims,
                                    const char* which) {
  Geometry g;
  g.dims = dims;
  for (int r = 0; r < 3; ++r) {
    const double sign = r < 2 ? -1.0 : 1.0;
    for (int c = 0; c < 4; ++c)
      if (!std::isfinite(ras.m[r][c])) return fail(path + ": the " + std::string(which) + " holds a non-finite number");
    for (int c = 0; c < 3; ++c) g.direction.m[r][c] = sign * ras.m[r][c];
    g.originMm[r] = sign * ras.m[r][3];
  }
  for (int c = 0; c < 3; ++c) {
    const double length = norm(g.direction.column(c));
    if (!(length > 1e-9))
      return fail(path + ": the " + std::string(which) + " gives axis " + std::to_string(c) + " zero spacing");
    g.spacingMm[c] = length;
    for (int r = 0; r < 3; ++r) g.direction.m[r][c] /= length;
  }
  if (std::abs(g.direction.determinant()) < 1e-6)
    return fail(path + ": the " + std::string(which) + " is singular (its axes are parallel)");
  return g;
}

}  // namespace

namespace {

Result<LoadedImage> readNifti(const std::string& path, const ImageLoadOptions& options) {
  quietNiftilib();
  if (!str::endsWith(path, ".nii") && !str::endsWith(path, ".nii.gz"))
    return fail(path + ": a NIfTI file name must end in .nii or .nii.gz");
  auto opened = openRegularFile(path, path);
  if (!opened) return tl::unexpected(opened.error());
  const std::uint64_t fileBytes = opened->sizeBytes;
  // zlib reads plain and gzip files alike through the descriptor (and closes it).
  GzFilePtr file(gzdopen(opened->fd.get(), "rb"));
  if (!file) return fail(ErrorKind::Io, path + ": cannot open the file");
  opened->fd.release();
  auto header = readNiftiHeader(path, file.get());
  if (!header) return tl::unexpected(header.error());
  NiftiImagePtr nim = std::move(header->nim);

  for (int d = 4; d <= 7; ++d)
    if (nim->dim[0] >= d && nim->dim[d] > 1)
      return fail(path + ": image has " + std::to_string(nim->dim[d]) + " entries along dimension " +
                  std::to_string(d) + "; only 3D images are supported");
  if (nim->nx < 1 || nim->ny < 1 || nim->nz < 1 || nim->nx > INT32_MAX || nim->ny > INT32_MAX || nim->nz > INT32_MAX)
    return fail(path + ": invalid dimensions " + std::to_string(nim->nx) + "x" + std::to_string(nim->ny) + "x" +
                std::to_string(nim->nz));
  const Dims dims{int(nim->nx), int(nim->ny), int(nim->nz)};

  ScalarKind kind;
  if (!kindOf(nim->datatype, kind))
    return fail(path + ": unsupported NIfTI datatype " + std::string(nifti_datatype_string(nim->datatype)) +
                " (supported: int8, uint8, int16, uint16, int32, uint32, float32, float64)");

  Result<Geometry> geometry;
  std::string geometryNote = "geometry from the sform";
  if (nim->sform_code > 0) geometry = geometryFromAffine(path, nim->sto_xyz, dims, "sform");
  if (nim->sform_code <= 0 || (!geometry && nim->qform_code > 0)) {
    // qform, or the plain pixdim scaling niftilib derives when qform_code is 0; also the fallback
    // when a writer set sform_code but left the sform degenerate.
    geometryNote = geometry || nim->sform_code <= 0 ? "geometry from the qform"
                                                    : "sform unusable (" + geometry.error().message + "); geometry from the qform";
    const double* d = header->pixdim;
    for (int a = 0; a < 3; ++a)
      if (!(d[a] > 0) || !std::isfinite(d[a]))
        return fail(path + ": pixdim[" + std::to_string(a + 1) + "] is " + std::to_string(d[a]) +
                    "; voxel spacing must be positive");
    geometry = geometryFromAffine(path, nim->qto_xyz, dims, "qform");
  }
  if (!geometry) return tl::unexpected(geometry.error());

  // Stored values are read and converted in pieces of this size: the only buffer besides the result.
  constexpr std::size_t kPiece = std::size_t(16) << 20;
  const std::size_t bytesPerVoxel = std::size_t(nim->nbyper);
  const std::size_t needBytes = dims.count() * bytesPerVoxel;
  const std::size_t pieceBytes = std::min(kPiece, needBytes);
  if (auto fits = detail::checkImageFits(path, dims, double(pieceBytes), options); !fits)
    return tl::unexpected(fits.error());

  // The file must hold exactly the voxel data its header describes. An uncompressed file's size
  // says so before anything is allocated; compressed data are checked as they arrive.
  const std::string sizeText =
      "dimensions " + dims.toString() + " × " + toString(kind) + " need " + std::to_string(needBytes) + " bytes";
  if (nim->iname_offset < 0) return fail(path + ": vox_offset is negative");
  const auto voxOffset = std::uint64_t(nim->iname_offset);
  if (gzdirect(file.get()) && fileBytes < voxOffset + needBytes)
    return fail(path + ": " + sizeText + " but the file holds " +
                std::to_string(fileBytes > voxOffset ? fileBytes - voxOffset : 0) + " after the header");
  if (gzrewind(file.get()) != 0 || gzseek(file.get(), z_off_t(nim->iname_offset), SEEK_SET) < 0)
    return fail(path + ": vox_offset " + std::to_string(nim->iname_offset) + " lies beyond the end of the file");

  double slope = nim->scl_slope, inter = nim->scl_inter;
  if (slope == 0.0 || !std::isfinite(slope) || !std::isfinite(inter)) {
    slope = 1.0;
    inter = 0.0;
  }
  LoadedImage loaded;
  loaded.storedKind = kind;
  loaded.image.geometry = *geometry;
  // A set scl_slope is the file's statement of the value scale (HU for CT, say), even 1 and 0.
  loaded.rescaleGiven = nim->scl_slope != 0.0 && std::isfinite(nim->scl_slope);
  std::vector<float>& out = loaded.image.voxels;
  // Address space for the whole image, but pages are only touched as converted values arrive: a
  // header claiming more than the file holds costs no memory.
  out.reserve(dims.count());
  std::vector<unsigned char> piece(pieceBytes);
  const bool swap = nim->byteorder != nifti_short_order() && nim->swapsize > 1;
  std::size_t got = 0;
  if (options.progress) options.progress(0, needBytes);
  while (got < needBytes) {
    if (detail::loadCancelled(options)) return tl::unexpected(detail::cancelledError(path));
    const std::size_t want = std::min(pieceBytes, needBytes - got);
    const long long read = gzReadFully(file.get(), piece.data(), want);
    if (read < 0) return fail(path + ": the compressed data is corrupt (" + gzMessage(file.get()) + ")");
    const std::size_t values = std::size_t(read) / bytesPerVoxel;
    if (swap) nifti_swap_Nbytes(int64_t(values), nim->swapsize, piece.data());
    const std::size_t at = out.size();
    out.resize(at + values);
    convertPiece(kind, piece.data(), out.data() + at, values, slope, inter);
    got += std::size_t(read);
    if (options.progress) options.progress(got, needBytes);
    if (std::size_t(read) < want)
      return fail(path + ": " + sizeText + " but the file holds " + std::to_string(got) + " after the header");
  }
  unsigned char extra = 0;
  const long long more = gzReadFully(file.get(), &extra, 1);
  if (more < 0) return fail(path + ": the compressed data is corrupt (" + gzMessage(file.get()) + ")");
  if (more > 0) return fail(path + ": " + sizeText + " but the file holds more data after the header");

  if (slope != 1.0 || inter != 0.0)
    loaded.notes.push_back("applied scl_slope " + std::to_string(slope) + ", scl_inter " + std::to_string(inter));
  loaded.notes.push_back(geometryNote);
  return loaded;
}

}  // namespace

Result<LoadedImage> loadNifti(const std::string& path, const ImageLoadOptions& options) {
  return withPrintableError(readNifti(path, options));
}

namespace {

template <class T>
Status writeNifti(const std::string& path, const Geometry& geometry, const std::vector<T>& voxels, int datatype) {
  quietNiftilib();
  if (!str::endsWith(path, ".nii") && !str::endsWith(path, ".nii.gz"))
    return fail(path + ": a NIfTI file name must end in .nii or .nii.gz");
  if (auto ok = checkOutputPath(path, path); !ok) return ok;
  const Dims& dims = geometry.dims;
  if (dims.count() == 0 || voxels.size() != dims.count()) return fail(path + ": image to write is empty");

  const int64_t dimArray[8] = {3, dims.x, dims.y, dims.z, 1, 1, 1, 1};
  NiftiImagePtr nim(nifti_make_new_nim(dimArray, datatype, 0));
  if (!nim) return fail(path + ": niftilib could not create the image");
  nim->nifti_type = NIFTI_FTYPE_NIFTI1_1;
  nim->xyz_units = NIFTI_UNITS_MM;

  // LPS geometry → RAS affine: negate the first two rows.
  nifti_dmat44 ras{};
  for (int r = 0; r < 3; ++r) {
    const double sign = r < 2 ? -1.0 : 1.0;
    for (int c = 0; c < 3; ++c) ras.m[r][c] = sign * geometry.direction.m[r][c] * geometry.spacingMm[c];
    ras.m[r][3] = sign * geometry.originMm[r];
  }
  ras.m[3][0] = ras.m[3][1] = ras.m[3][2] = 0;
  ras.m[3][3] = 1;
  nim->sform_code = NIFTI_XFORM_SCANNER_ANAT;
  nim->sto_xyz = ras;
  nim->sto_ijk = nifti_dmat44_inverse(ras);
  nim->qform_code = NIFTI_XFORM_SCANNER_ANAT;
  double dx, dy, dz, qfac;
  nifti_dmat44_to_quatern(ras, &nim->quatern_b, &nim->quatern_c, &nim->quatern_d, &nim->qoffset_x, &nim->qoffset_y,
                          &nim->qoffset_z, &dx, &dy, &dz, &qfac);
  nim->qfac = qfac;
  nim->dx = nim->pixdim[1] = geometry.spacingMm[0];
  nim->dy = nim->pixdim[2] = geometry.spacingMm[1];
  nim->dz = nim->pixdim[3] = geometry.spacingMm[2];
  nim->pixdim[0] = qfac;
  nim->qto_xyz = nifti_quatern_to_dmat44(nim->quatern_b, nim->quatern_c, nim->quatern_d, nim->qoffset_x,
                                         nim->qoffset_y, nim->qoffset_z, nim->dx, nim->dy, nim->dz, nim->qfac);
  nim->qto_ijk = nifti_dmat44_inverse(nim->qto_xyz);

  // The file is built here (header, empty extension flag, voxels) and written through AtomicFile,
  // not by nifti_image_write, which reports a full disk only on stderr and truncates the old file
  // before writing the new one.
  static_assert(sizeof(nifti_1_header) == 348, "a NIfTI-1 header is 348 bytes");
  nim->iname_offset = 352;
  nifti_1_header header{};
  if (nifti_convert_nim2n1hdr(nim.get(), &header) != 0) return fail(path + ": niftilib could not make the header");
  header.vox_offset = 352.0f;
  std::memcpy(header.magic, "n+1\0", 4);
  std::string bytes(reinterpret_cast<const char*>(&header), sizeof header);
  bytes.append(4, '\0');  // no extensions
  bytes.append(reinterpret_cast<const char*>(voxels.data()), voxels.size() * sizeof(T));
  if (str::endsWith(path, ".gz")) {
    auto compressed = gzipBytes(path, bytes);
    if (!compressed) return tl::unexpected(compressed.error());
    bytes = std::move(*compressed);
  }
  return writeFileAtomically(path, bytes);
}

}  // namespace

Status writeNiftiFloat(const std::string& path, const FloatVolume& image) {
  return writeNifti(path, image.geometry, image.voxels, DT_FLOAT32);
}

Status writeNiftiLabels(const std::string& path, const LabelMap& labels) {
  return writeNifti(path, labels.geometry, labels.voxels, DT_UINT16);
}

}  // namespace at
