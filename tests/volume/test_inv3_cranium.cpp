// The real head CT (Cranium.inv3 from Debian's invesalius-examples, fetched by
// scripts/fetch-scans.sh): geometry and values, orientation checked against anatomy the loader
// must place right (teeth inferior and anterior, mastoid air posterior-lateral, vertex superior),
// and the voxels docs/skull_landmarks.md names as seeds still holding their tissue.
// Skipped, with the reason, where the scan has not been fetched.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <vector>

#include "test_support.h"
#include "volume/image_file.h"
#include "volume/known_scans.h"

using namespace at;

namespace {

// Loaded once for the whole file: 7 million voxels.
const Result<Dataset>& loadedSkull() {
  static const Result<Dataset> loaded = openKnownScan(*findKnownScan("skull"));
  return loaded;
}
const Dataset* skull() { return loadedSkull() ? &*loadedSkull() : nullptr; }

bool requireSkull(const char* what) {
  const KnownScan* scan = findKnownScan("skull");
  if (!scan || !locateKnownScan(*scan)) {
    at::test::skipf("%s needs Cranium.inv3 from Debian's invesalius-examples (run scripts/fetch-scans.sh)", what);
    return false;
  }
  REQUIRE_MESSAGE(skull(), test::errorText(loadedSkull()));
  return true;
}

struct Centroid {
  Vec3 mm{0, 0, 0};
  std::size_t count = 0;
};

template <class Keep>
Centroid centroidOf(const Volume& v, Keep keep) {
  Centroid c;
  const Dims d = v.dims();
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (keep(i, j, k)) {
          const Vec3 p = v.geometry.indexToPatient({double(i), double(j), double(k)});
          for (int a = 0; a < 3; ++a) c.mm[std::size_t(a)] += p[std::size_t(a)];
          ++c.count;
        }
  if (c.count)
    for (double& x : c.mm) x /= double(c.count);
  return c;
}

// Air (< -400 HU) that no path of air within its axial slice joins to the slice's border: the
// air inside the head (sinuses, mastoid cells, airway), not the room around it.
std::vector<std::uint8_t> enclosedAir(const Volume& v) {
  const Dims d = v.dims();
  std::vector<std::uint8_t> inside(d.count(), 0);
  std::vector<std::uint8_t> reached(std::size_t(d.x) * std::size_t(d.y));
  for (int k = 0; k < d.z; ++k) {
    std::fill(reached.begin(), reached.end(), 0);
    std::deque<std::pair<int, int>> queue;
    const auto air = [&](int i, int j) { return v.at(i, j, k) < -400; };
    const auto push = [&](int i, int j) {
      if (i < 0 || j < 0 || i >= d.x || j >= d.y) return;
      std::uint8_t& r = reached[std::size_t(i) + std::size_t(d.x) * std::size_t(j)];
      if (r || !air(i, j)) return;
      r = 1;
      queue.emplace_back(i, j);
    };
    for (int i = 0; i < d.x; ++i) push(i, 0), push(i, d.y - 1);
    for (int j = 0; j < d.y; ++j) push(0, j), push(d.x - 1, j);
    while (!queue.empty()) {
      const auto [i, j] = queue.front();
      queue.pop_front();
      push(i + 1, j), push(i - 1, j), push(i, j + 1), push(i, j - 1);
    }
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (air(i, j) && !reached[std::size_t(i) + std::size_t(d.x) * std::size_t(j)]) inside[d.index(i, j, k)] = 1;
  }
  return inside;
}

std::int16_t huAt(const Volume& v, const Vec3& mm) {
  const Vec3 ijk = v.geometry.patientToIndex(mm);
  const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
  REQUIRE(v.dims().contains(i, j, k));
  return v.at(i, j, k);
}

}  // namespace

TEST_CASE("Cranium.inv3: 256x256x108 int16 HU at 0.957 x 0.957 x 1.5 mm, oriented LAS") {
  if (!requireSkull("the InVesalius skull geometry test")) return;
  const Volume& v = skull()->volume;
  CHECK(v.dims() == Dims{256, 256, 108});
  CHECK(v.geometry.spacingMm[0] == doctest::Approx(0.9570312).epsilon(1e-6));
  CHECK(v.geometry.spacingMm[1] == doctest::Approx(0.9570312).epsilon(1e-6));
  CHECK(v.geometry.spacingMm[2] == doctest::Approx(1.5));
  CHECK(v.geometry.orientationCode() == "LAS");
  const auto [lo, hi] = std::minmax_element(v.voxels.begin(), v.voxels.end());
  CHECK(*lo == -1024);                    // air outside the head, as the scanner writes it
  CHECK(*hi > 2500);                      // enamel
  CHECK(*hi < 3100);
  // Brain in the middle of the head: soft tissue, 0 … 60 HU.
  std::vector<std::int16_t> brain;
  for (int k = 60; k < 80; ++k)
    for (int j = 60; j < 100; ++j)
      for (int i = 110; i < 150; ++i) brain.push_back(v.at(i, j, k));
  std::nth_element(brain.begin(), brain.begin() + std::ptrdiff_t(brain.size() / 2), brain.end());
  CHECK(brain[brain.size() / 2] > 0);
  CHECK(brain[brain.size() / 2] < 60);
  CHECK(skull()->id == "skull");
  // Structures only from the labels set-up grows beside the scan (scripts/label-scans.sh).
  CHECK(skull()->structures.empty() == !cachedKnownScanLabels(*findKnownScan("skull")).has_value());
}

TEST_CASE("Cranium.inv3: the teeth lie inferior and anterior, the mastoid air posterior-lateral, the vault superior") {
  if (!requireSkull("the InVesalius skull orientation test")) return;
  const Volume& v = skull()->volume;
  const Dims d = v.dims();
  // Enamel (> 1800 HU) is the densest tissue: the upper teeth, at the bottom of the scan, in front.
  const Centroid teeth = centroidOf(v, [&](int i, int j, int k) { return v.at(i, j, k) > 1800; });
  REQUIRE(teeth.count > 500);
  CAPTURE(teeth.mm);
  CHECK(teeth.mm[2] < -60);               // inferior: the grid spans −80 … +80 mm
  CHECK(teeth.mm[1] < -45);               // anterior: −y in LPS
  CHECK(std::abs(teeth.mm[0]) < 20);      // near the midline

  // Enclosed air in the lower half, 35–65 mm from the midline on either side: mastoid air cells.
  const std::vector<std::uint8_t> inside = enclosedAir(v);
  for (const double side : {-1.0, 1.0}) {
    CAPTURE(side);
    const Centroid mastoid = centroidOf(v, [&](int i, int j, int k) {
      if (!inside[d.index(i, j, k)]) return false;
      const Vec3 p = v.geometry.indexToPatient({double(i), double(j), double(k)});
      return p[2] < 0 && side * p[0] > 35 && side * p[0] < 65;
    });
    REQUIRE(mastoid.count > 300);
    CAPTURE(mastoid.mm);
    CHECK(mastoid.mm[1] > teeth.mm[1] + 50);  // well behind the teeth
    CHECK(mastoid.mm[1] > 0);                 // in the posterior half of the grid
    CHECK(mastoid.mm[2] > -70);
    CHECK(mastoid.mm[2] < -30);
  }

  // Bone reaches the top slices (the vault), and the top slice holds no tissue below the vault's.
  int topBoneSlice = -1;
  for (int k = 0; k < d.z; ++k)
    for (std::size_t n = std::size_t(k) * d.x * d.y; n < std::size_t(k + 1) * d.x * d.y && topBoneSlice < k; ++n)
      if (v.voxels[n] > 300) topBoneSlice = k;
  CHECK(topBoneSlice >= 100);
  CHECK(v.geometry.indexToPatient({0, 0, double(topBoneSlice)})[2] > 70);
}

TEST_CASE("Cranium.inv3: the seed voxels of docs/skull_landmarks.md hold their tissue") {
  if (!requireSkull("the InVesalius skull landmarks test")) return;
  const Volume& v = skull()->volume;
  struct Landmark {
    const char* name;
    Vec3 mm;
    int minHu, maxHu;
  };
  const Landmark landmarks[] = {
      {"teeth", {22.5, -63.6, -78.8}, 1800, 4000},
      {"mandible, right ramus", {-41.6, -19.6, -68.2}, 300, 1800},
      {"mandible, left ramus", {49.3, -21.5, -68.2}, 300, 1800},
      {"maxilla", {4.3, -61.7, -62.2}, 300, 1800},
      {"zygomatic arch, left", {58.9, -9.1, -50.2}, 300, 3000},
      {"nasal cavity", {-0.5, -38.8, -48.8}, -3000, -400},
      {"maxillary sinus, right", {-18.7, -46.4, -48.8}, -3000, -400},
      {"maxillary sinus, left", {26.3, -51.2, -45.8}, -3000, -400},
      {"frontal sinus", {0.5, -68.4, 2.2}, -3000, -400},
      {"sphenoid sinus", {2.4, -19.6, -33.8}, -3000, -400},
      {"ethmoid cells", {4.3, -38.8, -26.2}, -3000, -400},
      {"orbit, right", {-33.0, -49.3, -21.8}, -150, 100},
      {"orbit, left", {34.0, -52.2, -20.2}, -150, 100},
      {"mastoid air cells, right", {-58.9, 25.4, -50.2}, -3000, -400},
      {"mastoid air cells, left", {54.1, 22.5, -45.8}, -3000, -400},
      {"external acoustic meatus, right", {-47.4, 9.1, -47.2}, -3000, -400},
      {"external acoustic meatus, left", {52.2, 11.0, -47.2}, -3000, -400},
      {"petrous bone, right", {-32.1, 14.8, -45.8}, 1000, 3000},
      {"petrous bone, left", {37.8, 13.9, -45.8}, 1000, 3000},
      {"C1 lateral mass, right", {-17.7, 12.0, -78.8}, 300, 3000},
      {"C1 lateral mass, left", {20.6, 12.0, -78.8}, 300, 3000},
      {"C2 dens", {1.4, 8.1, -75.8}, 300, 3000},
  };
  for (const Landmark& l : landmarks) {
    CAPTURE(l.name);
    const int hu = huAt(v, l.mm);
    CAPTURE(hu);
    CHECK(hu >= l.minHu);
    CHECK(hu <= l.maxHu);
  }
}
