// InVesalius 3 projects (.inv3) made here with libarchive: geometry and values read back, member
// order and compression variants, and every broken input as a one-line error naming the file.
#include <doctest/doctest.h>

#include <atomic>
#include <fstream>

#include "inv3_test_files.h"
#include "io_test_files.h"
#include "test_support.h"
#include "volume/image_file.h"
#include "volume/inv3_io.h"

using namespace at;
using namespace at::test;

namespace {

void checkTestImage(const LoadedImage& loaded) {
  const Geometry& g = loaded.image.geometry;
  CHECK(g.dims == Dims{kInv3X, kInv3Y, kInv3Z});
  CHECK(g.spacingMm[0] == doctest::Approx(0.5));
  CHECK(g.spacingMm[1] == doctest::Approx(0.75));
  CHECK(g.spacingMm[2] == doctest::Approx(2.0));
  CHECK(g.orientationCode() == "LAS");
  CHECK((loaded.storedKind == ScalarKind::Int16));
  // The grid is centred on (0,0,0) mm; +i is left, +j anterior (−y in LPS), +k superior.
  const Vec3 centre = g.centreMm();
  for (int a = 0; a < 3; ++a) CHECK(centre[std::size_t(a)] == doctest::Approx(0.0).epsilon(1e-9));
  const Vec3 p000 = g.indexToPatient({0, 0, 0}), p111 = g.indexToPatient({1, 1, 1});
  CHECK(p111[0] - p000[0] == doctest::Approx(0.5));
  CHECK(p111[1] - p000[1] == doctest::Approx(-0.75));
  CHECK(p111[2] - p000[2] == doctest::Approx(2.0));
  int mismatches = 0;
  for (int z = 0; z < kInv3Z; ++z)
    for (int y = 0; y < kInv3Y; ++y)
      for (int x = 0; x < kInv3X; ++x)
        if (loaded.image.at(x, y, z) != float(inv3TestValue(x, y, z))) ++mismatches;
  CHECK(mismatches == 0);
}

}  // namespace

TEST_CASE("InVesalius: a gzip project reads back its shape, spacing, axes and every value") {
  TempDir dir;
  const auto path = dir / "head.inv3";
  writeInv3(path);
  auto loaded = loadInv3(path.string());
  REQUIRE_MESSAGE(loaded, test::errorText(loaded));
  checkTestImage(*loaded);
  REQUIRE(!loaded->notes.empty());
  CHECK(loaded->notes[0].find("modality CT") != std::string::npos);
  // The patient name in main.plist is never copied out.
  for (const std::string& note : loaded->notes) CHECK(note.find("Test Patient") == std::string::npos);
}

TEST_CASE("InVesalius: a plain tar with the matrix before main.plist, in any folder, reads the same") {
  TempDir dir;
  const auto path = dir / "head.inv3";
  const Inv3Plist plist;
  writeTar(path, {{"a/b/matrix.dat", "decoy"}, {"proj/matrix.dat", inv3Matrix()}, {"proj/main.plist", plist.xml()}},
           /*gzip=*/false);
  auto loaded = loadInv3(path.string());
  REQUIRE_MESSAGE(loaded, test::errorText(loaded));
  checkTestImage(*loaded);
}

TEST_CASE("InVesalius: loadImageFile picks the loader from .inv3 (any case) and the values convert to HU") {
  TempDir dir;
  const auto path = dir / "HEAD.INV3";
  writeInv3(path);
  auto loaded = loadImageFile(path.string());
  REQUIRE_MESSAGE(loaded, test::errorText(loaded));
  checkTestImage(*loaded);
  auto hu = toHuVolume(*loaded, path.string());
  REQUIRE(hu);
  CHECK(hu->at(6, 4, 2) == inv3TestValue(6, 4, 2));
}

TEST_CASE("InVesalius: other numpy dtypes (uint8, float32) read as their values") {
  TempDir dir;
  SUBCASE("uint8") {
    Inv3Plist plist;
    plist.matrix["dtype"] = "<string>uint8</string>";
    std::string matrix;
    for (int n = 0; n < kInv3X * kInv3Y * kInv3Z; ++n) matrix.push_back(char(n * 2));
    writeInv3(dir / "u8.inv3", plist, matrix);
    auto loaded = loadInv3((dir / "u8.inv3").string());
    REQUIRE_MESSAGE(loaded, test::errorText(loaded));
    CHECK((loaded->storedKind == ScalarKind::UInt8));
    CHECK(loaded->image.at(1, 0, 0) == 2.0f);
    CHECK(loaded->image.at(6, 4, 2) == float((kInv3X * kInv3Y * kInv3Z - 1) * 2));
  }
  SUBCASE("float32") {
    Inv3Plist plist;
    plist.matrix["dtype"] = "<string>float32</string>";
    std::string matrix;
    for (int n = 0; n < kInv3X * kInv3Y * kInv3Z; ++n) {
      const float v = -0.5f * float(n);
      char b[4];
      std::memcpy(b, &v, 4);
      matrix.append(b, 4);
    }
    writeInv3(dir / "f32.inv3", plist, matrix);
    auto loaded = loadInv3((dir / "f32.inv3").string());
    REQUIRE_MESSAGE(loaded, test::errorText(loaded));
    CHECK((loaded->storedKind == ScalarKind::Float32));
    CHECK(loaded->image.at(3, 0, 0) == -1.5f);
  }
}

TEST_CASE("InVesalius: progress reports the matrix bytes and cancelling stops the load") {
  TempDir dir;
  const auto path = (dir / "head.inv3").string();
  writeInv3(path);
  ImageLoadOptions options;
  std::size_t lastDone = 0, lastTotal = 0;
  options.progress = [&](std::size_t done, std::size_t total) { lastDone = done, lastTotal = total; };
  REQUIRE(loadInv3(path, options));
  CHECK(lastTotal == std::size_t(kInv3X * kInv3Y * kInv3Z * 2));
  CHECK(lastDone == lastTotal);

  std::atomic<bool> cancel{true};
  options.cancel = &cancel;
  checkError(loadInv3(path, options), path, "loading cancelled");
}

TEST_CASE("InVesalius: broken archives are one-line errors naming the file and the problem") {
  TempDir dir;
  const std::string path = (dir / "head.inv3").string();

  SUBCASE("missing file") { checkError(loadInv3(path), path, "no such file"); }
  SUBCASE("not an archive") {
    writeBytes(path, "this is a text file, not a tar archive\n");
    checkError(loadInv3(path), path, "not an InVesalius project, or a damaged one (expected a tar archive, gzip-compressed or plain: Unrecognized archive format)");
  }
  SUBCASE("empty file") {
    writeBytes(path, "");
    checkError(loadInv3(path), path, "not an InVesalius project");
  }
  SUBCASE("truncated in the matrix") {
    // Random matrix values so that gzip cannot shrink them: the cut falls inside matrix.dat.
    std::string matrix = inv3Matrix(256, 256, 8);
    std::uint32_t state = 12345;
    for (char& c : matrix) c = char((state = state * 1664525u + 1013904223u) >> 24);
    Inv3Plist plist;
    plist.matrix["shape"] = "<array><integer>8</integer><integer>256</integer><integer>256</integer></array>";
    writeInv3(path, plist, matrix);
    const std::string bytes = readBytes(path);
    writeBytes(path, bytes.substr(0, bytes.size() * 2 / 3));
    checkError(loadInv3(path), path, "the archive is damaged or truncated in member 'tmpproject/matrix.dat'");
  }
  SUBCASE("truncated within the first block") {
    writeInv3(path);
    writeBytes(path, readBytes(path).substr(0, 40));
    checkError(loadInv3(path), path, "or a damaged one");
  }
  SUBCASE("unreadable") {
    writeInv3(path);
    std::filesystem::permissions(path, std::filesystem::perms::none);
    if (std::ifstream(path)) return;  // root reads anything: nothing to test
    checkError(loadInv3(path), path, "cannot open the file for reading");
  }
  SUBCASE("truncated before the second member") {
    writeTar(path, {{"p/main.plist", Inv3Plist{}.xml()}, {"p/matrix.dat", inv3Matrix()}}, /*gzip=*/false);
    const std::string bytes = readBytes(path);
    writeBytes(path, bytes.substr(0, 1024 + 100));  // the plist's header and block, then part of the next header
    checkError(loadInv3(path), path, "damaged or truncated");
  }
  SUBCASE("no main.plist") {
    writeTar(path, {{"p/matrix.dat", inv3Matrix()}, {"p/mask_0.plist", "x"}});
    checkError(loadInv3(path), path, "no main.plist in the archive, so not an InVesalius 3 project (members: p/matrix.dat, p/mask_0.plist)");
  }
  SUBCASE("no matrix member") {
    writeTar(path, {{"p/main.plist", Inv3Plist{}.xml()}, {"other/matrix.dat", inv3Matrix()}});
    checkError(loadInv3(path), path, "main.plist names the matrix 'matrix.dat' but the archive has no member 'p/matrix.dat'");
  }
  SUBCASE("matrix shorter than the shape") {
    writeInv3(path, {}, inv3Matrix().substr(2));
    checkError(loadInv3(path), path, "tmpproject/matrix.dat holds 208 bytes but shape 3x5x7 (z,y,x) × int16 needs 210 bytes");
  }
  SUBCASE("matrix longer than the shape") {
    writeInv3(path, {}, inv3Matrix() + "xx");
    checkError(loadInv3(path), path, "holds 212 bytes but shape 3x5x7 (z,y,x) × int16 needs 210 bytes");
  }
  SUBCASE("image over the memory limit") {
    ImageLoadOptions options;
    options.maxBytes = 100;
    writeInv3(path);
    checkError(loadInv3(path, options), path, "memory limit");
  }
}

TEST_CASE("InVesalius: a main.plist that lacks or garbles a field names the field") {
  TempDir dir;
  const std::string path = (dir / "head.inv3").string();
  Inv3Plist plist;
  std::string expected;

  SUBCASE("not a plist") {
    writeTar(path, {{"p/main.plist", "<html>not a plist"}, {"p/matrix.dat", inv3Matrix()}});
    checkError(loadInv3(path), path, "p/main.plist is not a property list");
    return;
  }
  SUBCASE("plist is an array") {
    writeTar(path, {{"p/main.plist", "<?xml version=\"1.0\"?><plist version=\"1.0\"><array/></plist>"}});
    checkError(loadInv3(path), path, "the property list is not a dictionary");
    return;
  }
  SUBCASE("no matrix dictionary") {
    plist.withMatrix = false;
    expected = "no 'matrix' dictionary";
  }
  SUBCASE("shape with two entries") {
    plist.matrix["shape"] = "<array><integer>3</integer><integer>5</integer></array>";
    expected = "'matrix.shape' must be 3 positive integers (z, y, x)";
  }
  SUBCASE("negative shape") {
    plist.matrix["shape"] = "<array><integer>3</integer><integer>-5</integer><integer>7</integer></array>";
    expected = "'matrix.shape' must be 3 positive integers";
  }
  SUBCASE("real-valued shape") {
    plist.matrix["shape"] = "<array><integer>3</integer><real>5.5</real><integer>7</integer></array>";
    expected = "'matrix.shape' must be 3 positive integers";
  }
  SUBCASE("huge shape") {
    plist.matrix["shape"] = "<array><integer>3</integer><integer>5</integer><integer>70000</integer></array>";
    expected = "of at most 65535";
  }
  SUBCASE("no dtype") {
    plist.matrix["dtype"] = "";
    expected = "'matrix.dtype' is missing or not a string";
  }
  SUBCASE("unsupported dtype") {
    plist.matrix["dtype"] = "<string>complex64</string>";
    expected = "unsupported 'matrix.dtype' 'complex64' (supported: int8, uint8, int16";
  }
  SUBCASE("filename with a path") {
    plist.matrix["filename"] = "<string>../../etc/passwd</string>";
    expected = "'matrix.filename' must name a member beside main.plist";
  }
  SUBCASE("no spacing") {
    plist.top["spacing"] = "";
    expected = "'spacing' must be 3 positive numbers in mm (x, y, z)";
  }
  SUBCASE("zero spacing") {
    plist.top["spacing"] = "<array><real>0.5</real><real>0</real><real>1</real></array>";
    expected = "'spacing' must be 3 positive numbers";
  }
  SUBCASE("text spacing") {
    plist.top["spacing"] = "<array><real>0.5</real><string>1</string><real>1</real></array>";
    expected = "'spacing' must be 3 positive numbers";
  }
  if (!std::filesystem::exists(path)) writeInv3(path, plist);
  checkError(loadInv3(path), path, path + ": tmpproject/main.plist: " + expected);
}
