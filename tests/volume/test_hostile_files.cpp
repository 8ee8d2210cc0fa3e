// Hostile files: what the fuzzers and a set of hand-made files found, each pinned by a
// test that failed before its fix. Headers that claim more than their files hold must cost no
// memory; FIFOs and devices are refused without blocking; data files stay where they may be read;
// the memory limit follows the process's cgroup.
#include <doctest/doctest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <string>
#include <thread>

#include <dcmtk/config/osconfig.h>
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <zlib.h>

#include "io_test_files.h"
#include "test_support.h"
#include "volume/dicom_seg.h"
#include "volume/dicom_series.h"
#include "volume/image_file.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"

using namespace at;
using namespace at::test;
namespace fs = std::filesystem;

namespace {

// Peak resident memory (VmHWM) of this process since the last reset, in MiB; -1 if unavailable.
long peakRssMib() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmHWM:") {
      long kib = 0;
      status >> kib;
      return kib / 1024;
    }
    status.ignore(1 << 20, '\n');
  }
  return -1;
}

// Resets VmHWM to the current resident size (Linux: "5" to /proc/self/clear_refs).
bool resetPeakRss() {
  std::ofstream clear("/proc/self/clear_refs");
  clear << "5";
  clear.flush();
  return bool(clear);
}

// Runs `load` and returns how far the peak resident memory rose meanwhile (MiB), or -1 when the
// peak cannot be measured here.
template <class Load>
long peakRiseMib(Load load) {
  if (!resetPeakRss()) return -1;
  const long before = peakRssMib();
  load();
  const long after = peakRssMib();
  return before < 0 || after < 0 ? -1 : after - before;
}

template <class T>
std::string errorOf(const Result<T>& result) {
  REQUIRE_FALSE(result.has_value());
  const std::string& message = result.error().message;
  CHECK(message.find('\n') == std::string::npos);
  return message;
}

// A native (uncompressed, explicit VR little endian) CT slice of rows × columns int16 pixels,
// whose PixelData holds `pixelCount` values (fewer than rows × columns for a hostile header).
void writeCtSlice(const fs::path& path, int rows, int columns, std::size_t pixelCount, double z) {
  DcmFileFormat file;
  DcmDataset& d = *file.getDataset();
  d.putAndInsertString(DCM_SOPClassUID, UID_CTImageStorage);
  d.putAndInsertString(DCM_SeriesInstanceUID, "1.2.826.0.1.3680043.9.7133.25.1");
  d.putAndInsertUint16(DCM_Rows, Uint16(rows));
  d.putAndInsertUint16(DCM_Columns, Uint16(columns));
  d.putAndInsertUint16(DCM_SamplesPerPixel, 1);
  d.putAndInsertString(DCM_PhotometricInterpretation, "MONOCHROME2");
  d.putAndInsertUint16(DCM_BitsAllocated, 16);
  d.putAndInsertUint16(DCM_BitsStored, 16);
  d.putAndInsertUint16(DCM_HighBit, 15);
  d.putAndInsertUint16(DCM_PixelRepresentation, 1);
  d.putAndInsertString(DCM_PixelSpacing, "0.5\\0.5");
  d.putAndInsertString(DCM_ImageOrientationPatient, "1\\0\\0\\0\\1\\0");
  d.putAndInsertString(DCM_ImagePositionPatient, ("0\\0\\" + std::to_string(z)).c_str());
  std::vector<Uint16> pixels(pixelCount, 100);
  d.putAndInsertUint16Array(DCM_PixelData, pixels.data(), static_cast<unsigned long>(pixels.size()));
  REQUIRE(file.saveFile(OFFilename(path.c_str()), EXS_LittleEndianExplicit).good());
}

// A FIFO that unblocks any reader after `seconds` (by opening and closing its write end), so that
// a test of a reader that would block forever fails instead of hanging. `unblocked()`: a reader
// still had it open then (opening the write end without blocking succeeds only when one has) —
// it waited on the FIFO, however fast or slow the machine.
class WatchedFifo {
 public:
  WatchedFifo(const fs::path& path, int seconds) : path_(path) {
    REQUIRE(::mkfifo(path.c_str(), 0600) == 0);
    watchdog_ = std::thread([this, seconds] {
      for (int i = 0; i < seconds * 10 && !done_; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (done_) return;
      const int fd = ::open(path_.c_str(), O_WRONLY | O_NONBLOCK);
      if (fd >= 0) unblocked_ = true, ::close(fd);
    });
  }
  ~WatchedFifo() {
    done_ = true;
    watchdog_.join();
  }
  bool unblocked() const { return unblocked_; }

 private:
  fs::path path_;
  std::atomic<bool> done_{false}, unblocked_{false};
  std::thread watchdog_;
};

template <class Load>
double secondsTaken(Load load) {
  const auto start = std::chrono::steady_clock::now();
  load();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

TEST_CASE("NRRD: 'space directions' and 'kinds' listing more axes than the dimension are read safely") {
  // Found by fuzz_nrrd: a 'none' or non-domain kind at index ≥ dimension indexed `sizes` past its end.
  const fs::path found = sourceDir() / "tests/fuzz/regressions/nrrd/space_directions_beyond_dimension.nrrd";
  auto loaded = loadNrrd(found.string());
  if (!loaded) CHECK(loaded.error().message.rfind(found.string() + ": ", 0) == 0);
  TempDir dir;
  const fs::path path = dir / "five.nrrd";
  writeBytes(path, std::string("NRRD0004\ntype: uchar\ndimension: 4\nsizes: 1 2 2 2\n"
                               "space directions: none (1,0,0) (0,1,0) (0,0,1) none\nkinds: list domain domain domain list\n"
                               "encoding: raw\n\n") +
                       std::string(8, '\x01'));
  auto five = loadNrrd(path.string());
  REQUIRE_MESSAGE(five, five.error().message);
  CHECK(five->image.dims().toString() == "2x2x2");
}

TEST_CASE("NIfTI: a header claiming 600³ int16 voxels that the file lacks is refused without allocating them") {
  TempDir dir;
  RawNifti claim;
  claim.dims[0] = claim.dims[1] = claim.dims[2] = 600;  // 432 MB of int16, 216 M voxels
  const std::string path = (dir / "claim.nii").string();
  writeBytes(path, claim.bytes());
  ImageLoadOptions options;
  options.maxBytes = std::size_t(4) << 30;  // the limit does not stop it: the missing data must
  Result<LoadedImage> loaded = fail("not run");
  const long rise = peakRiseMib([&] { loaded = loadNifti(path, options); });
  CHECK(errorOf(loaded) == path + ": dimensions 600x600x600 × int16 need 432000000 bytes but the file holds 0 after the header");
  if (rise < 0) {
    MESSAGE("partly skipped: peak memory (VmHWM reset) cannot be measured here");
  } else {
    CAPTURE(rise);
    CHECK(rise < 64);  // it once zero-filled 432 MB for the data before reading any
  }
}

TEST_CASE("DICOM: a slice claiming 8000x8000 pixels with 64 stored is refused before the volume is allocated") {
  TempDir dir;
  writeCtSlice(dir / "claim.dcm", 8000, 8000, 64, 0);
  ImageLoadOptions options;
  options.maxBytes = std::size_t(4) << 30;
  Result<LoadedImage> loaded = fail("not run");
  const long rise = peakRiseMib([&] { loaded = loadDicomSeries(dir.path().string(), options); });
  const std::string message = errorOf(loaded);
  CHECK(message.find("claim.dcm: PixelData holds 128 bytes but 8000x8000 × 16 bits need 128000000") != std::string::npos);
  if (rise >= 0) {
    CAPTURE(rise);
    CHECK(rise < 64);  // it once allocated and zeroed 256 MB of floats first
  }
}

TEST_CASE("DICOM: PixelData with a VR other than OB/OW is refused, not cast to DcmPixelData") {
  // Found by fuzz_dicom_series under UBSan: the element class DCMTK builds for another VR was
  // static_cast to DcmPixelData (undefined behaviour).
  TempDir dir;
  writeCtSlice(dir / "slice.dcm", 4, 4, 16, 0);
  std::string bytes = readBytes(dir / "slice.dcm");
  const std::size_t tag = bytes.find(std::string("\xe0\x7f\x10\x00OW", 6));
  REQUIRE(tag != std::string::npos);
  bytes.replace(tag + 4, 2, "UN");
  writeBytes(dir / "slice.dcm", bytes);
  CHECK(errorOf(loadDicomSeries(dir.path().string())).find("slice.dcm: PixelData has the value representation UN, not OB or OW") !=
        std::string::npos);
}

TEST_CASE("DICOM: unreadable files fail the series by name, or are skipped with a note when asked") {
  TempDir dir;
  for (int k = 0; k < 4; ++k) writeCtSlice(dir / ("s" + std::to_string(k) + ".dcm"), 4, 4, 16, 2.0 * k);
  // The last slice cut after its preamble: a header DCMTK cannot read.
  std::string cut = readBytes(dir / "s3.dcm");
  writeBytes(dir / "s3.dcm", cut.substr(0, 200));
  const std::string message = errorOf(loadDicomSeries(dir.path().string()));
  CHECK(message.find("s3.dcm: cannot read DICOM file") != std::string::npos);
  CHECK(message.find("(unreadable files can be skipped: --skip-unreadable)") != std::string::npos);

  ImageLoadOptions skip;
  skip.skipUnreadableFiles = true;
  auto loaded = loadDicomSeries(dir.path().string(), skip);
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  CHECK(loaded->image.dims().toString() == "4x4x3");
  bool noted = false;
  for (const auto& note : loaded->notes) noted = noted || note.rfind("skipped 1 unreadable file: s3.dcm: ", 0) == 0;
  CHECK_MESSAGE(noted, "notes name the skipped file");

  // A slice cut inside its PixelData is skipped the same way.
  writeCtSlice(dir / "s3.dcm", 4, 4, 16, 6.0);
  std::string truncated = readBytes(dir / "s3.dcm");
  writeBytes(dir / "s3.dcm", truncated.substr(0, truncated.size() - 10));
  CHECK(errorOf(loadDicomSeries(dir.path().string())).find("s3.dcm: cannot read DICOM file (") != std::string::npos);
  CHECK(loadDicomSeries(dir.path().string(), skip));
}

TEST_CASE("FIFOs and devices are refused at once, never read or waited on") {
  TempDir dir;
  WatchedFifo fifo(dir / "pipe", 5);
  WatchedFifo niiFifo(dir / "pipe.nii", 5);
  WatchedFifo jsonFifo(dir / "names.json", 5);
  std::string messages;
  messages += errorOf(loadImageFile((dir / "pipe").string())) + "\n";
  messages += errorOf(loadNifti((dir / "pipe.nii").string())) + "\n";
  messages += errorOf(loadLabelNames((dir / "names.json").string())) + "\n";
  CAPTURE(messages);
  // `info` on a FIFO once blocked until something wrote to it: no watchdog had to unblock a reader
  // (checked so instead of by a wall-clock bound, which a stalled machine could fail).
  CHECK_FALSE(fifo.unblocked());
  CHECK_FALSE(niiFifo.unblocked());
  CHECK_FALSE(jsonFifo.unblocked());
  CHECK(messages.find((dir / "pipe").string() + ": is a FIFO (named pipe), not a regular file") != std::string::npos);
  CHECK(messages.find((dir / "pipe.nii").string() + ": is a FIFO (named pipe), not a regular file") != std::string::npos);
  CHECK(messages.find((dir / "names.json").string() + ": is a FIFO (named pipe), not a regular file") != std::string::npos);
  CHECK(errorOf(loadImageFile("/dev/zero")) == "/dev/zero: is a device, not a regular file");
  CHECK(errorOf(loadLabelNames("/dev/urandom")) == "/dev/urandom: is a device, not a regular file");
}

TEST_CASE("NRRD: detached data files must lie in the header's folder unless the user names another") {
  TempDir dir;
  fs::create_directories(dir / "course");
  fs::create_directories(dir / "elsewhere");
  writeBytes(dir / "elsewhere" / "data.raw", std::string(8, '\x02'));
  const std::string header = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 2 2 2\nencoding: raw\n";
  const fs::path up = dir / "course" / "up.nhdr", absolute = dir / "course" / "absolute.nhdr";
  writeBytes(up, header + "data file: ../elsewhere/data.raw\n");
  writeBytes(absolute, header + "data file: " + (dir / "elsewhere" / "data.raw").string() + "\n");
  for (const fs::path& p : {up, absolute}) {
    const std::string message = errorOf(loadNrrd(p.string()));
    CHECK(message.find("lies outside the header's folder") != std::string::npos);
    CHECK(message.find("--nrrd-data DIR") != std::string::npos);
  }
  // A link inside the folder that leads out of it is resolved first.
  fs::create_symlink(dir / "elsewhere" / "data.raw", dir / "course" / "link.raw");
  writeBytes(dir / "course" / "link.nhdr", header + "data file: link.raw\n");
  CHECK(errorOf(loadNrrd((dir / "course" / "link.nhdr").string())).find("lies outside") != std::string::npos);
  writeBytes(dir / "course" / "inside.raw", std::string(8, '\x03'));
  writeBytes(dir / "course" / "inside.nhdr", header + "data file: inside.raw\n");
  CHECK(loadNrrd((dir / "course" / "inside.nhdr").string()));
  // The user may allow another folder explicitly.
  ImageLoadOptions allowed;
  allowed.dataFolder = dir.path().string();
  auto loaded = loadNrrd(up.string(), allowed);
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  CHECK(loaded->image.voxels[0] == 2.0f);
  CHECK(loadNrrd(absolute.string(), allowed));
}

TEST_CASE("Memory limit: 3/4 of what the cgroup (v1 or v2) leaves free, else of MemAvailable") {
  TempDir dir;
  const fs::path meminfo = dir / "meminfo", self = dir / "cgroup", root = dir / "sys";
  writeBytes(meminfo, "MemTotal: 33554432 kB\nMemFree: 1000 kB\nMemAvailable: 16777216 kB\n");  // 16 GiB
  MemoryInfoFiles files{meminfo.string(), self.string(), root.string()};

  writeBytes(self, "0::/\n");  // cgroup v2, no limit anywhere
  fs::create_directories(root);
  writeBytes(root / "memory.max", "max\n");
  MemoryBudget budget = imageMemoryBudget(files);
  CHECK(budget.bytes == std::size_t(12) << 30);
  CHECK(budget.source == "3/4 of the 16.0 GiB free under the machine's available memory");

  // v2: a 4 GiB limit two levels up, 1.5 GiB in use of which 0.5 GiB is reclaimable file cache.
  writeBytes(self, "0::/user.slice/app.scope\n");
  fs::create_directories(root / "user.slice" / "app.scope");
  writeBytes(root / "user.slice" / "memory.max", "4294967296\n");
  writeBytes(root / "user.slice" / "memory.current", "1610612736\n");
  writeBytes(root / "user.slice" / "memory.stat", "anon 1073741824\ninactive_file 536870912\n");
  writeBytes(root / "user.slice" / "app.scope" / "memory.max", "max\n");
  budget = imageMemoryBudget(files);
  CHECK(budget.bytes == std::size_t(9) << 28);  // 3/4 of the 4 − (1.5 − 0.5) = 3 GiB left
  CHECK(budget.source == "3/4 of the 3.0 GiB free under this process's cgroup memory limit");

  // v1: the memory controller's hierarchy; "no limit" is a page-rounded 2^63 − 1.
  fs::remove_all(root);
  writeBytes(self, "12:cpuset:/\n4:memory:/docker/abc\n1:name=systemd:/\n");
  fs::create_directories(root / "memory" / "docker" / "abc");
  writeBytes(root / "memory" / "memory.limit_in_bytes", "9223372036854771712\n");
  writeBytes(root / "memory" / "docker" / "abc" / "memory.limit_in_bytes", "2147483648\n");
  writeBytes(root / "memory" / "docker" / "abc" / "memory.usage_in_bytes", "1073741824\n");
  budget = imageMemoryBudget(files);
  CHECK(budget.bytes == std::size_t(768) << 20);
  CHECK(budget.source == "3/4 of the 1.0 GiB free under this process's cgroup memory limit");

  // Nothing readable: a fixed 2 GiB.
  budget = imageMemoryBudget(MemoryInfoFiles{(dir / "none").string(), (dir / "none").string(), (dir / "none").string()});
  CHECK(budget.bytes == std::size_t(2) << 30);
}

TEST_CASE("NIfTI: a gzip bomb over the memory limit is refused before it inflates, counting every buffer") {
  // 512x512x256 int16 zeros: 128 MiB inflated from a few hundred kB. As floats alone (256 MiB) it
  // passed a 300 MiB limit and then peaked at 384 MiB (stored + floats), over the limit it named.
  TempDir dir;
  RawNifti bomb;
  bomb.dims[0] = bomb.dims[1] = 512;
  bomb.dims[2] = 256;
  const std::string path = (dir / "bomb.nii.gz").string();
  {
    gzFile out = gzopen(path.c_str(), "wb9");
    REQUIRE(out);
    const std::string header = bomb.bytes();
    gzwrite(out, header.data(), unsigned(header.size()));
    const std::string zeros(1 << 20, '\0');
    for (int i = 0; i < 128; ++i) gzwrite(out, zeros.data(), unsigned(zeros.size()));
    gzclose(out);
  }
  ImageLoadOptions options;
  options.maxBytes = std::size_t(300) << 20;
  std::size_t inflated = 0;
  options.progress = [&](std::size_t done, std::size_t) { inflated = std::max(inflated, done); };
  const std::string message = errorOf(loadNifti(path, options));
  CHECK(message.find("needs 400.0 MiB (float voxels, their HU or label copy and read buffers) but only 300.0 MiB may be used") !=
        std::string::npos);
  CHECK(inflated == 0);
  options.maxBytes = std::size_t(401) << 20;
  CHECK(loadNifti(path, options));
}

TEST_CASE("NIfTI and NRRD: data that inflate beyond the header's claim are refused after one byte too many") {
  // 4x4x4 int16 claimed, then 1 GiB of gzip members: reading stops one byte past the 128 claimed.
  TempDir dir;
  RawNifti small;
  small.dims[0] = small.dims[1] = small.dims[2] = 4;
  small.data.assign(128, '\0');
  std::string member;
  {
    const std::string zeros(std::size_t(64) << 20, '\0');
    uLongf size = compressBound(uLong(zeros.size())) + 64;
    std::string deflated(size, '\0');
    z_stream zs{};
    REQUIRE(deflateInit2(&zs, 9, Z_DEFLATED, 15 + 16, 9, Z_DEFAULT_STRATEGY) == Z_OK);
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(zeros.data()));
    zs.avail_in = uInt(zeros.size());
    zs.next_out = reinterpret_cast<Bytef*>(deflated.data());
    zs.avail_out = uInt(deflated.size());
    REQUIRE(deflate(&zs, Z_FINISH) == Z_STREAM_END);
    deflated.resize(zs.total_out);
    deflateEnd(&zs);
    member = deflated;
  }
  const std::string path = (dir / "small.nii.gz").string();
  {
    gzFile out = gzopen(path.c_str(), "wb");
    const std::string bytes = small.bytes();
    gzwrite(out, bytes.data(), unsigned(bytes.size()));
    gzclose(out);
  }
  std::string file = readBytes(path);
  for (int i = 0; i < 16; ++i) file += member;  // 16 × 64 MiB of zeros more
  writeBytes(path, file);
  Result<LoadedImage> loaded = fail("not run");
  const double seconds = secondsTaken([&] { loaded = loadNifti(path); });
  CHECK(errorOf(loaded).find("but the file holds more data after the header") != std::string::npos);
  CHECK(seconds < 2.0);
}

TEST_CASE("DICOM SEG: a segmentation DCMTK fails to read is released (DCMTK's loadDataset leaked it)") {
  // Found by fuzz_dicom_seg under LeakSanitizer; the sanitizer run of this test catches a relapse.
  const fs::path found = sourceDir() / "tests/fuzz/regressions/dicom_seg/read_fails_after_allocation.dcm";
  const std::string message = errorOf(loadDicomSeg(found.string()));
  CHECK(message.rfind(found.string() + ": cannot read the segmentation", 0) == 0);
}
