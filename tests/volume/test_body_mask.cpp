// The body mask: what is anatomy (kept for the context) and what is a headrest, a table or a
// loose object (left out), on a scene whose parts are known voxel by voxel.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>

#include "volume/body_mask.h"

using namespace at;

namespace {

constexpr std::int16_t kAir = -1000, kTissue = 40, kBone = 800, kPlastic = 200;

enum class Part { Air, Head, Nose, Ear, Bridge, Headrest, HolderWall, Cable };

// A head (an ellipsoid of soft tissue) with a hollow nose (a 2 mm wall, 23 mm long) and a thin ear
// (a 3 mm plate), resting on a headrest (an 11 mm slab) through a 2 × 2 mm contact; a 2 mm side
// wall of the holder rises beside the head without touching it; a 2 mm cable lies apart. Every
// thin part is thinner than the 6 mm that the default erosion (3 mm half-width) takes off.
struct Scene {
  Volume volume;
  std::vector<Part> part;
};

Scene makeScene(double spacingMm) {
  Scene s;
  const int n = int(std::lround(120 / spacingMm)), nz = int(std::lround(80 / spacingMm));
  s.volume.geometry.dims = {n, n, nz};
  s.volume.geometry.spacingMm = {spacingMm, spacingMm, spacingMm};
  s.volume.voxels.assign(s.volume.geometry.dims.count(), kAir);
  s.part.assign(s.volume.voxels.size(), Part::Air);
  const auto inHead = [](double x, double y, double z) {
    return std::pow((x - 60) / 35, 2) + std::pow((y - 60) / 35, 2) + std::pow((z - 45) / 25, 2) <= 1;
  };
  std::size_t p = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i, ++p) {
        const double x = (i + 0.5) * spacingMm, y = (j + 0.5) * spacingMm, z = (k + 0.5) * spacingMm;
        const double noseR = std::hypot(x - 60, z - 45);
        Part what = Part::Air;
        std::int16_t hu = kAir;
        if (inHead(x, y, z)) {
          what = Part::Head;
          hu = kTissue;
        } else if (y >= 2 && y < 30 && noseR >= 3 && noseR < 5) {
          what = Part::Nose;  // in front of the face (the head's front is at y 25)
          hu = z > 48 ? kBone : kTissue;  // the nasal bones on top
        } else if (x >= 90 && x < 108 && y >= 55 && y < 70 && z >= 40 && z < 43) {
          what = Part::Ear;
          hu = kTissue;
        } else if (x >= 59 && x < 61 && y >= 59 && y < 61 && z >= 15 && z < 21) {
          what = Part::Bridge;
          hu = kPlastic;
        } else if (x >= 20 && x < 100 && y >= 20 && y < 100 && z >= 4 && z < 15) {
          what = Part::Headrest;
          hu = kPlastic;
        } else if (x >= 20 && x < 100 && y >= 100 && y < 102 && z >= 15 && z < 40) {
          what = Part::HolderWall;
          hu = kPlastic;
        } else if (x >= 5 && x < 115 && y >= 110 && y < 112 && z >= 60 && z < 62) {
          what = Part::Cable;
          hu = kPlastic;
        }
        s.part[p] = what;
        s.volume.voxels[p] = hu;
      }
  return s;
}

struct Tally {
  std::size_t voxels = 0, inBody = 0;
};

Tally tally(const Scene& s, const Mask& body, Part which) {
  Tally t;
  for (std::size_t p = 0; p < s.part.size(); ++p)
    if (s.part[p] == which) {
      ++t.voxels;
      t.inBody += body.voxels[p] != 0;
    }
  return t;
}

}  // namespace

TEST_CASE("The body mask keeps the head with its thin nose and ears, and leaves out the headrest, the holder and a loose cable") {
  for (double spacing : {1.0, 0.5}) {
    CAPTURE(spacing);
    const Scene scene = makeScene(spacing);
    const Mask body = bodyMask(scene.volume, -300);
    REQUIRE(body.voxels.size() == scene.volume.voxels.size());
    const auto show = [&](const char* name, Part which) {
      const Tally t = tally(scene, body, which);
      MESSAGE(std::string(name) << ": " << t.inBody << " of " << t.voxels << " voxels in the body");
      REQUIRE(t.voxels > 0);
      return t;
    };
    const Tally head = show("head", Part::Head), nose = show("nose", Part::Nose), ear = show("ear", Part::Ear);
    const Tally rest = show("headrest", Part::Headrest), wall = show("holder wall", Part::HolderWall);
    const Tally cable = show("cable", Part::Cable);
    // Anatomy, however thin and however far it reaches from the head: all of it.
    CHECK(head.inBody == head.voxels);
    CHECK(nose.inBody == nose.voxels);
    CHECK(ear.inBody == ear.voxels);
    // Objects: none of them, whether thick, thin and joined to a thick one, or loose.
    CHECK(rest.inBody == 0);
    CHECK(wall.inBody == 0);
    CHECK(cable.inBody == 0);
  }
}

TEST_CASE("The body mask of a scan thinner than its erosion everywhere is its largest piece") {
  // A 4 mm plate of tissue (a thin animal part, a slice of a specimen) and a smaller plate apart.
  Volume v;
  v.geometry.dims = {40, 40, 20};
  v.voxels.assign(v.geometry.dims.count(), kAir);
  std::size_t p = 0, plate = 0, other = 0;
  std::vector<int> kind(v.voxels.size(), 0);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i, ++p) {
        if (k >= 8 && k < 12 && j >= 5 && j < 35 && i >= 5 && i < 25) kind[p] = 1;
        if (k >= 8 && k < 12 && j >= 5 && j < 15 && i >= 30 && i < 38) kind[p] = 2;
        if (kind[p]) v.voxels[p] = kTissue;
      }
  const Mask body = bodyMask(v, -300);
  for (std::size_t q = 0; q < kind.size(); ++q) {
    plate += kind[q] == 1 && body.voxels[q];
    other += kind[q] == 2 && body.voxels[q];
  }
  CHECK(plate == 20u * 30u * 4u);
  CHECK(other == 0);
}
