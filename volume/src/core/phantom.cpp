// The synthetic temporal-bone phantom (see volume/phantom.h for its purpose).
//
// Convention: a RIGHT temporal bone in LPS millimetres, the cube centred at 0, identity direction.
//   lateral  = −x (patient right, towards the skin and the external auditory canal)
//   medial   = +x (towards the posterior cranial fossa, where the internal auditory canal opens)
//   anterior = −y, posterior = +y, superior = +z.
// All anatomy is placed in millimetres, so every grid size shows the same anatomy; only tubes
// thinner than about one voxel are widened to 0.9 voxel so that they stay connected on coarse grids.
//
// How it is built: a list of paint operations (shapes with a material and a label) applied in
// order over a base: a rounded block of bone (cortical shell over cancellous bone) in a layer of
// soft tissue, outside air lateral to the skin and brain everywhere else around it. Later operations win. Each worker thread owns a slab of z-slices and runs every
// operation clipped to its slab and to the shape's bounding box, so the result does not depend on
// the number of threads. HU come last: each material's value, a smooth texture for cancellous bone
// (fixed, part of the anatomy) and per-voxel noise from the seed (splitmix64 of seed and voxel
// index; an Irwin–Hall sum keeps it independent of any standard library's distributions).
//
// Paint order (why it is this order):
//   base → temporal line ridge → petrous bone (dense, around the labyrinth and towards the apex)
//   → sigmoid sinus and carotid canal (cortical wall, then blood)
//   → mastoid antrum and aditus, then the air cells as a honeycomb (Voronoi cells of seeded points,
//     separated by thin bony septa) → internal auditory canal (CSF)
//   → otic capsule (dense bone within 1.3 mm of every labyrinth lumen; caps the IAC fundus)
//   → labyrinth lumens (canals, cochlea, vestibule last so that canals open into it)
//   → tympanic cavity and oval-window niche → external auditory canal → tympanic membrane
//   → fallopian canal wall and facial nerve → ossicles (the stapes footplate seals the oval window).
#include "volume/phantom.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "core/parallel_rows.h"

namespace at {

namespace {

// --- small deterministic random numbers -------------------------------------------------------

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

class SplitMix {
 public:
  explicit SplitMix(std::uint64_t seed) : state_(seed) {}
  // Uniform in [0, 1) from the top 53 bits.
  double uniform() {
    state_ += 0x9E3779B97F4A7C15ULL;
    return double(splitmix64(state_ - 0x9E3779B97F4A7C15ULL) >> 11) * (1.0 / 9007199254740992.0);
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }

 private:
  std::uint64_t state_;
};

// The anatomy (cell positions, bone texture) uses this fixed seed; options.seed only drives noise,
// so two seeds give the same labels and HU that differ by noise alone.
constexpr std::uint64_t kAnatomySeed = 0x7E3B0C4A11D5F0A1ULL;

// --- materials and HU ------------------------------------------------------------------------------

enum Material : std::uint8_t {
  kAir, kSoftTissue, kFluid, kCsf, kBlood, kCancellous, kCortical, kCapsule, kOssicle, kNerve, kMembrane, kPetrous,
  kBrain
};

constexpr double kNoiseSigmaHu = 20.0;   // after the point-spread function
constexpr double kPsfSigmaMm = 0.2;      // Gaussian blur of the scanner (FWHM ≈ 0.47 mm)

double materialHu(Material m) {
  switch (m) {
    case kAir: return -1000;
    case kSoftTissue: return 40;
    case kFluid: return 8;
    case kCsf: return 10;
    case kBlood: return 50;
    case kCancellous: return 600;  // ± 100 from the texture
    case kCortical: return 1850;
    case kCapsule: return 2000;
    case kPetrous: return 1800;  // fused with the otic capsule (2000): no surface between them
    case kBrain: return 35;
    case kOssicle: return 1350;
    case kNerve: return 35;
    case kMembrane: return 45;
  }
  return 0;
}

// --- shapes (signed distance in mm, negative inside) ------------------------------------------

double clamp01(double t) { return t < 0 ? 0 : (t > 1 ? 1 : t); }
Vec3 unit(const Vec3& v) { return (1.0 / norm(v)) * v; }

struct Shape {
  enum Kind { kSegment, kEllipsoid, kSuperEllipsoid, kCylinder, kTorus, kCustom } kind = kSegment;
  Vec3 a{0, 0, 0}, b{0, 0, 0};  // segment/cylinder ends; a = centre otherwise
  double ra = 0, rb = 0;        // segment radii at a and b; cylinder radius; torus minor radius
  Vec3 radii{1, 1, 1};          // ellipsoid semi-axes (axis-aligned)
  Vec3 normal{0, 0, 1};         // torus plane normal
  double majorR = 0;            // torus major radius
  std::shared_ptr<const std::function<double(const Vec3&)>> custom;  // kCustom: its sd …
  Vec3 boxLo{0, 0, 0}, boxHi{0, 0, 0};                               // … within this box

  double sd(const Vec3& p) const {
    switch (kind) {
      case kSegment: {
        const Vec3 ba = b - a, pa = p - a;
        const double h = clamp01(dot(pa, ba) / dot(ba, ba));
        return norm(pa - h * ba) - (ra + (rb - ra) * h);
      }
      case kEllipsoid: {
        const Vec3 q = p - a;
        const Vec3 s{q[0] / radii[0], q[1] / radii[1], q[2] / radii[2]};
        const Vec3 s2{s[0] / radii[0], s[1] / radii[1], s[2] / radii[2]};
        const double k0 = norm(s), k1 = norm(s2);
        if (k1 == 0) return -std::min({radii[0], radii[1], radii[2]});
        return k0 * (k0 - 1) / k1;
      }
      case kSuperEllipsoid: {  // |x/rx|^4 + |y/ry|^4 + |z/rz|^4 = 1, a rounded box
        const Vec3 q = p - a;
        double s = 0;
        for (int i = 0; i < 3; ++i) {
          const double t = q[i] / radii[i];
          s += t * t * t * t;
        }
        return (std::sqrt(std::sqrt(s)) - 1) * std::min({radii[0], radii[1], radii[2]});
      }
      case kCylinder: {
        const Vec3 axis = b - a;
        const double len = norm(axis);
        const Vec3 u = (1.0 / len) * axis;
        const double t = dot(p - a, u);
        const double q = norm(p - a - t * u);
        const double dx = q - ra, dy = std::max(-t, t - len);
        const double ox = std::max(dx, 0.0), oy = std::max(dy, 0.0);
        return std::min(std::max(dx, dy), 0.0) + std::sqrt(ox * ox + oy * oy);
      }
      case kTorus: {
        const Vec3 q = p - a;
        const double z = dot(q, normal);
        const double rho = norm(q - z * normal) - majorR;
        return std::sqrt(rho * rho + z * z) - ra;
      }
      case kCustom: return (*custom)(p);
    }
    return 1e9;
  }

  void bounds(Vec3& lo, Vec3& hi) const {
    switch (kind) {
      case kSegment:
      case kCylinder: {
        const double r = std::max(ra, rb);
        for (int i = 0; i < 3; ++i) {
          lo[i] = std::min(a[i], b[i]) - r;
          hi[i] = std::max(a[i], b[i]) + r;
        }
        return;
      }
      case kEllipsoid:
      case kSuperEllipsoid:
        lo = a - radii;
        hi = a + radii;
        return;
      case kTorus: {
        const double r = majorR + ra;
        lo = a - Vec3{r, r, r};
        hi = a + Vec3{r, r, r};
        return;
      }
      case kCustom:
        lo = boxLo;
        hi = boxHi;
        return;
    }
  }
};

Shape segment(const Vec3& a, const Vec3& b, double ra, double rb = -1) {
  Shape s;
  s.kind = Shape::kSegment;
  s.a = a;
  s.b = b;
  s.ra = ra;
  s.rb = rb < 0 ? ra : rb;
  return s;
}
Shape ellipsoid(const Vec3& centre, const Vec3& radii) {
  Shape s;
  s.kind = Shape::kEllipsoid;
  s.a = centre;
  s.radii = radii;
  return s;
}
Shape superEllipsoid(const Vec3& centre, const Vec3& radii) {
  Shape s = ellipsoid(centre, radii);
  s.kind = Shape::kSuperEllipsoid;
  return s;
}
Shape cylinder(const Vec3& a, const Vec3& b, double r) {
  Shape s = segment(a, b, r);
  s.kind = Shape::kCylinder;
  return s;
}
Shape torus(const Vec3& centre, const Vec3& normal, double majorR, double minorR) {
  Shape s;
  s.kind = Shape::kTorus;
  s.a = centre;
  s.normal = unit(normal);
  s.majorR = majorR;
  s.ra = minorR;
  return s;
}

// A tube along a polyline, one tapered segment per edge.
std::vector<Shape> tube(const std::vector<Vec3>& points, double r) {
  std::vector<Shape> out;
  for (std::size_t i = 0; i + 1 < points.size(); ++i) out.push_back(segment(points[i], points[i + 1], r));
  return out;
}

// --- the base: a rounded block of bone wrapped in soft tissue ----------------------------------

const Vec3 kBlockCentre{1.5, 1.0, -1.0};
const Vec3 kBlockHalf{14.5, 18.0, 14.0};  // x −13…16, y −17…19, z −15…13
constexpr double kBlockRounding = 3.0;
constexpr double kCortexMm = 1.5;
constexpr double kSoftTissueMm = 3.5;
// The lateral skin plane: outside air beyond it (x below), where the external auditory canal opens.
const double kSkinX = kBlockCentre[0] - kBlockHalf[0] - kSoftTissueMm;

double blockSd(const Vec3& p) {
  double outside = 0, inside = -1e9;
  for (int i = 0; i < 3; ++i) {
    const double q = std::abs(p[i] - kBlockCentre[i]) - kBlockHalf[i] + kBlockRounding;
    if (q > 0) outside += q * q;
    inside = std::max(inside, q);
  }
  return std::sqrt(outside) + std::min(inside, 0.0) - kBlockRounding;
}

// --- the anatomy -------------------------------------------------------------------------------

// Label values (index + 1 in phantomStructures()).
namespace label {
enum : std::uint16_t {
  kCochlea = 1, kVestibule, kLateralCanal, kPosteriorCanal, kSuperiorCanal, kFacialNerve,
  kInternalAuditoryCanal, kExternalAuditoryCanal, kTympanicCavity, kMalleus, kIncus, kStapes,
  kMastoidAirCells, kSigmoidSinus, kCarotidCanal, kTemporalLine
};
}  // namespace label

enum class Where { kAny, kUnlabelled, kUnlabelledOrMastoid };

struct PaintOp {
  std::vector<Shape> shapes;
  double growMm = 0;  // paint where sd ≤ growMm (a shell around the shapes)
  Material material = kAir;
  std::uint16_t label = 0;
  Where where = Where::kAny;
};

// Key points of the labyrinth, shared by several structures.
const Vec3 kVestibule{2.4, 1.0, 0.0};
const Vec3 kVestibuleRadii{1.6, 2.4, 2.6};
constexpr double kCanalMajorMm = 3.0;   // 6 mm loops
constexpr double kCanalLumenMm = 0.45;  // 0.9 mm lumen
constexpr double kCapsuleMm = 1.3;
const Vec3 kCochleaBase{4.4, -4.6, -2.2};
const double kOvalWindowZ = -1.5;

struct Anatomy {
  std::vector<PaintOp> ops;
};

Anatomy buildAnatomy(double voxelMm) {
  const double minTubeRadiusMm = 0.9 * voxelMm;
  const double r2 = std::sqrt(0.5);
  auto tubeR = [&](double r) { return std::max(r, minTubeRadiusMm); };
  Anatomy an;
  auto add = [&](std::vector<Shape> shapes, Material m, std::uint16_t label, Where where = Where::kAny,
                 double grow = 0) {
    PaintOp op;
    op.shapes = std::move(shapes);
    op.material = m;
    op.label = label;
    op.where = where;
    op.growMm = grow;
    an.ops.push_back(std::move(op));
  };

  // Temporal line: a cortical ridge on the lateral surface (x = −13) above the EAC, arching
  // slightly upwards in its middle, running antero-posteriorly.
  {
    std::vector<Vec3> pts;
    for (int i = 0; i <= 12; ++i) {
      const double y = -12.0 + 2.0 * i;
      pts.push_back({-13.0, y, 7.0 + 1.5 * (1 - (y / 12) * (y / 12))});
    }
    add(tube(pts, 1.1), kCortical, label::kTemporalLine);
  }

  // Petrous bone: the dense pyramid medial to the labyrinth that holds the internal auditory canal
  // and the carotid canal, from the cochlea anteromedially to the apex (medial face of the block),
  // inside the cortex; nearly as dense as the otic capsule it fuses with. Lateral to it (the
  // promontory side, seen from the middle ear) and behind it the bone stays cancellous.
  {
    Shape petrous;
    petrous.kind = Shape::kCustom;
    const Shape axis = segment({6.5, -2.5, -1.0}, {16.0, -14.0, -4.0}, 5.0, 4.5);
    axis.bounds(petrous.boxLo, petrous.boxHi);
    petrous.custom = std::make_shared<const std::function<double(const Vec3&)>>(
        [axis](const Vec3& p) { return std::max(axis.sd(p), blockSd(p) + kCortexMm); });
    add({petrous}, kPetrous, 0);
  }

  // Sigmoid sinus: an S-curved venous channel posterior-medial, behind the mastoid, descending
  // to the jugular bulb; a 1 mm cortical plate around blood.
  const std::vector<Vec3> sigmoid = {{6.0, 16.0, 10.0}, {7.5, 14.5, 4.0}, {8.5, 13.0, -3.0},
                                     {8.0, 12.0, -9.0}, {6.5, 10.5, -13.5}};
  add(tube(sigmoid, 2.4), kCortical, 0, Where::kAny, 1.0);
  add(tube(sigmoid, 2.4), kBlood, label::kSigmoidSinus);

  // Carotid canal: ascends vertically anterior-inferior to the cochlea, then turns anteromedially
  // towards the petrous apex; blood and soft tissue inside a cortical wall.
  const std::vector<Vec3> carotid = {{3.8, -10.8, -16.0}, {3.8, -10.8, -8.0}, {6.0, -11.8, -6.2},
                                     {14.0, -13.5, -5.2}};
  add(tube(carotid, 1.9), kCortical, 0, Where::kAny, 0.8);
  add(tube(carotid, 1.9), kBlood, label::kCarotidCanal);

  // Facial nerve centreline (used for the nerve itself and to keep air cells away from it):
  // IAC fundus → labyrinthine segment over the cochlea → geniculate ganglion (sharp turn) →
  // tympanic segment posteriorly on the medial wall of the tympanic cavity, between the lateral
  // canal above and the oval window below → second genu → mastoid segment straight down.
  const std::vector<Vec3> facial = {{7.5, -2.6, 1.5},  {4.5, -4.6, 3.2},  {1.5, -6.2, 3.6},
                                    {0.6, -6.0, 3.2},  {-1.2, -4.0, 1.2}, {-1.6, -1.0, 0.4},
                                    {-1.8, 2.5, 0.4},  {-2.4, 5.0, -0.4}, {-2.8, 5.8, -2.5},
                                    {-3.0, 6.0, -15.5}};

  // Semicircular canals: three mutually orthogonal loops. The petrous axis runs anteromedially,
  // (1, −1, 0)/√2; the superior canal's plane is perpendicular to it, the posterior canal's plane
  // parallel to it (both vertical), the lateral canal's plane horizontal.
  const double lateralAngle = 125.0 * 3.14159265358979323846 / 180.0;  // posterolateral
  const Vec3 lateralCentre = kVestibule + Vec3{3.4 * std::cos(lateralAngle), 3.4 * std::sin(lateralAngle), 1.7};
  const Vec3 superiorCentre = kVestibule + Vec3{0, 0, 5.4};
  const Vec3 e1{r2, -r2, 0};  // in the posterior canal's plane
  const Vec3 posteriorCentre = kVestibule + 3.2 * unit(-0.45 * e1 + Vec3{0, 0, -0.89});
  const Shape lateralCanal = torus(lateralCentre, {0, 0, 1}, kCanalMajorMm, tubeR(kCanalLumenMm));
  const Shape superiorCanal = torus(superiorCentre, {r2, -r2, 0}, kCanalMajorMm, tubeR(kCanalLumenMm));
  const Shape posteriorCanal = torus(posteriorCentre, {r2, r2, 0}, kCanalMajorMm, tubeR(kCanalLumenMm));

  // Cochlea: a 2.5-turn spiral tube around an axis pointing anterolaterally and down (the apex),
  // base ring radius 3.3 mm (≈ 8 mm across with the lumen), 4.2 mm rise (≈ 5.5 mm high), lumen
  // radius tapering 0.7 → 0.35 mm: successive turns lie about 1.9 mm apart, so about half a
  // millimetre of bone separates them and the spiral lumen reads as a spiral. The basal turn starts
  // next to the vestibule and a short connection opens it into the vestibule (scala vestibuli), so
  // fluid joins them.
  std::vector<Shape> cochlea;
  {
    const Vec3 axis = unit({-0.5, -0.75, -0.3});
    Vec3 u = unit(kVestibule - kCochleaBase);
    u = unit(u - dot(u, axis) * axis);
    const Vec3 v = cross(axis, u);
    const int steps = 150;
    const double turns = 2.5, rise = 4.2;
    Vec3 prev{};
    double prevR = 0;
    for (int s = 0; s <= steps; ++s) {
      const double t = double(s) / steps;
      const double angle = t * turns * 2 * 3.14159265358979323846;
      const double ringR = 3.3 - 2.4 * t;
      const Vec3 p = kCochleaBase + ringR * std::cos(angle) * u + ringR * std::sin(angle) * v + (rise * t) * axis;
      const double lumen = tubeR(0.7 - 0.35 * t);
      if (s == 0) {
        cochlea.push_back(segment(p, kVestibule + Vec3{-0.2, -1.4, -0.6}, lumen, tubeR(0.7)));
      } else {
        cochlea.push_back(segment(prev, p, prevR, lumen));
      }
      prev = p;
      prevR = lumen;
    }
  }
  const Shape vestibule = ellipsoid(kVestibule, kVestibuleRadii);

  // Tympanic cavity (a rounded box of air lateral to the promontory), the oval-window niche
  // leading from it to the vestibule, and the EAC from the skin to the tympanic membrane.
  const Shape tympanic = superEllipsoid({-4.5, -2.8, 1.0}, {2.2, 4.5, 5.5});
  const Shape niche = cylinder({-3.2, kVestibule[1], kOvalWindowZ}, {0.5, kVestibule[1], kOvalWindowZ}, 0.8);
  const Shape eac = cylinder({-16.4, -2.5, 0.0}, {-7.3, -2.5, 0.0}, 3.2);
  const Shape membrane = cylinder({-7.4, -2.5, 0.0}, {-6.2, -2.5, 0.0}, 3.2);

  // Mastoid antrum (a large cell reached from the epitympanum through the aditus) and the air
  // cells: a honeycomb in cancellous bone posterolaterally — the Voronoi cells of seeded points
  // 2.2–3.4 mm apart, air wherever a point is farther than half a septum from the plane between its
  // two nearest seeds, so thin bony septa separate the cells — kept inside the bone and away from
  // the nerve, the sinus, the labyrinth, the cavity and the EAC. A septum is at least √3 voxels
  // thick (coarse grids widen it as they widen thin tubes), so no two cells touch even diagonally.
  {
    const Shape antrum = ellipsoid({-5.2, 5.8, 3.6}, {1.8, 1.8, 1.6});
    const Shape aditus = segment({-5.0, 1.6, 4.2}, {-5.2, 5.0, 3.8}, 1.0);
    auto keepOut = std::make_shared<std::vector<std::pair<Shape, double>>>();  // shape and margin in mm
    for (const Shape& s : tube(facial, 0.55)) keepOut->push_back({s, 1.0});
    for (const Shape& s : tube(sigmoid, 2.4)) keepOut->push_back({s, 1.4});
    keepOut->push_back({lateralCanal, 1.6});
    keepOut->push_back({posteriorCanal, 1.6});
    keepOut->push_back({superiorCanal, 1.6});
    keepOut->push_back({vestibule, 1.6});
    keepOut->push_back({tympanic, 0.8});
    keepOut->push_back({eac, 0.8});
    keepOut->push_back({antrum, 0.4});
    keepOut->push_back({aditus, 0.4});
    const Vec3 regionCentre{-6.5, 10.0, -2.0}, regionRadii{4.8, 7.0, 8.5};
    auto seeds = std::make_shared<std::vector<std::pair<Vec3, double>>>();  // point and spacing
    SplitMix rng(kAnatomySeed);
    for (int attempt = 0; attempt < 6000 && seeds->size() < 400; ++attempt) {
      const Vec3 c{rng.uniform(-1.1, 1.1), rng.uniform(-1.1, 1.1), rng.uniform(-1.1, 1.1)};
      const double spacing = rng.uniform(2.2, 3.4);
      if (dot(c, c) > 1.21) continue;
      const Vec3 p{regionCentre[0] + c[0] * regionRadii[0], regionCentre[1] + c[1] * regionRadii[1],
                   regionCentre[2] + c[2] * regionRadii[2]};
      bool clear = true;
      for (const auto& [q, qs] : *seeds)
        if (norm(p - q) < std::max(spacing, qs)) {
          clear = false;
          break;
        }
      if (clear) seeds->push_back({p, spacing});
    }
    const double halfSeptum = std::max(0.18, 0.87 * voxelMm);
    // The region the cells fill (inside the ellipsoid, inside the bone, clear of every keep-out),
    // and the cells: the region less half a septum on either side of each Voronoi face.
    const auto region = [keepOut, regionCentre, regionRadii](const Vec3& p) {
      const Vec3 q{(p[0] - regionCentre[0]) / regionRadii[0], (p[1] - regionCentre[1]) / regionRadii[1],
                   (p[2] - regionCentre[2]) / regionRadii[2]};
      double sd = (norm(q) - 1.0) * regionRadii[0];
      if (sd > 0) return sd;
      sd = std::max(sd, blockSd(p) + kCortexMm + 0.6);
      if (sd > 0) return sd;
      for (const auto& [shape, margin] : *keepOut) {
        sd = std::max(sd, margin - shape.sd(p));
        if (sd > 0) return sd;
      }
      return sd;
    };
    const auto cells = [region, seeds, halfSeptum](const Vec3& p) {
      const double sd = region(p);
      if (sd > 0) return sd;
      // The two nearest seeds and the distance to the plane between them.
      double d1 = 1e30, d2 = 1e30;
      const Vec3* s1 = nullptr;
      const Vec3* s2 = nullptr;
      for (const auto& [c, spacing] : *seeds) {
        const double d = dot(p - c, p - c);
        if (d < d1) {
          d2 = d1;
          s2 = s1;
          d1 = d;
          s1 = &c;
        } else if (d < d2) {
          d2 = d;
          s2 = &c;
        }
      }
      if (!s2) return 1.0;
      const double toPlane = (d2 - d1) / (2.0 * norm(*s2 - *s1));
      return std::max(sd, halfSeptum - toPlane);
    };
    const auto customShape = [&](std::function<double(const Vec3&)> sd) {
      Shape shape;
      shape.kind = Shape::kCustom;
      shape.boxLo = regionCentre - regionRadii;
      shape.boxHi = regionCentre + regionRadii;
      shape.custom = std::make_shared<const std::function<double(const Vec3&)>>(std::move(sd));
      return shape;
    };
    // The septa are thin compact bone, as in a real mastoid.
    add({customShape(region)}, kCortical, 0, Where::kUnlabelled);
    add({antrum, aditus}, kAir, label::kMastoidAirCells);
    add({customShape(cells)}, kAir, label::kMastoidAirCells, Where::kUnlabelled);
  }

  // Internal auditory canal: CSF from its fundus next to the cochlea and vestibule to the medial
  // (posterior fossa) face of the bone at x = 16.
  add({segment({6.8, -2.0, 0.3}, {16.2, -0.5, 0.8}, 1.9)}, kCsf, label::kInternalAuditoryCanal);

  // Otic capsule around every labyrinth lumen, then the lumens.
  {
    std::vector<Shape> labyrinth = cochlea;
    labyrinth.push_back(vestibule);
    labyrinth.push_back(lateralCanal);
    labyrinth.push_back(posteriorCanal);
    labyrinth.push_back(superiorCanal);
    add(labyrinth, kCapsule, 0, Where::kAny, kCapsuleMm);
  }
  add({lateralCanal}, kFluid, label::kLateralCanal);
  add({posteriorCanal}, kFluid, label::kPosteriorCanal);
  add({superiorCanal}, kFluid, label::kSuperiorCanal);
  add(cochlea, kFluid, label::kCochlea);
  add({vestibule}, kFluid, label::kVestibule);

  add({tympanic, niche}, kAir, label::kTympanicCavity);
  add({eac}, kAir, label::kExternalAuditoryCanal);
  add({membrane}, kMembrane, 0, Where::kUnlabelled);

  add(tube(facial, tubeR(0.55)), kCortical, 0, Where::kUnlabelledOrMastoid, 0.35);
  add(tube(facial, tubeR(0.55)), kNerve, label::kFacialNerve);

  // Ossicles. Malleus: head in the epitympanum, neck, handle against the tympanic membrane.
  add({ellipsoid({-5.3, -2.3, 4.0}, {0.9, 1.1, 1.3}), segment({-5.3, -2.3, 3.0}, {-6.2, -2.4, 2.0}, tubeR(0.4)),
       segment({-6.2, -2.4, 2.0}, {-6.45, -2.5, -0.3}, tubeR(0.35))},
      kOssicle, label::kMalleus);
  // Incus: body articulating with the malleus head, short process posteriorly, long process
  // descending to the lenticular process at the stapes head.
  add({ellipsoid({-5.0, -0.1, 4.0}, {1.0, 1.2, 1.3}), segment({-5.0, -0.1, 4.0}, {-4.8, 1.2, 4.3}, tubeR(0.45)),
       segment({-5.1, 0.2, 3.0}, {-3.2, 1.0, -1.1}, tubeR(0.35)),
       segment({-3.2, 1.0, -1.1}, {-2.6, 1.0, kOvalWindowZ}, tubeR(0.35))},
      kOssicle, label::kIncus);
  // Stapes: head, two crura, and the footplate sealing the oval window of the vestibule.
  {
    const double y = kVestibule[1], z = kOvalWindowZ;
    add({ellipsoid({-2.3, y, z}, {0.4, 0.4, 0.4}), segment({-2.3, y, z}, {0.9, y + 0.55, z}, tubeR(0.22)),
         segment({-2.3, y, z}, {0.9, y - 0.55, z}, tubeR(0.22)), cylinder({0.45, y, z}, {1.3, y, z}, 1.1)},
        kOssicle, label::kStapes);
  }
  return an;
}

// --- painting ---------------------------------------------------------------------------------

struct Canvas {
  int n = 0;
  double spacing = 0, origin = 0;  // same on all axes
  std::vector<std::uint8_t>* material = nullptr;
  std::vector<std::uint16_t>* labels = nullptr;

  double coord(int i) const { return origin + spacing * i; }
  void indexRange(double lo, double hi, int& i0, int& i1) const {
    i0 = std::max(0, int(std::ceil((lo - origin) / spacing)));
    i1 = std::min(n - 1, int(std::floor((hi - origin) / spacing)));
  }
};

bool allowed(Where where, std::uint16_t current) {
  switch (where) {
    case Where::kAny: return true;
    case Where::kUnlabelled: return current == 0;
    case Where::kUnlabelledOrMastoid: return current == 0 || current == label::kMastoidAirCells;
  }
  return false;
}

void paintBase(const Canvas& c, int k0, int k1) {
  // blockSd split by axis: the y and z terms are constant along a row.
  const int n = c.n;
  std::vector<double> rowQ(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) rowQ[std::size_t(i)] = std::abs(c.coord(i) - kBlockCentre[0]) - kBlockHalf[0] + kBlockRounding;
  for (int k = k0; k < k1; ++k)
    for (int j = 0; j < n; ++j) {
      const double qy = std::abs(c.coord(j) - kBlockCentre[1]) - kBlockHalf[1] + kBlockRounding;
      const double qz = std::abs(c.coord(k) - kBlockCentre[2]) - kBlockHalf[2] + kBlockRounding;
      const double outsideYz = (qy > 0 ? qy * qy : 0) + (qz > 0 ? qz * qz : 0);
      const double insideYz = std::max(qy, qz);
      std::size_t idx = std::size_t(n) * (std::size_t(j) + std::size_t(n) * std::size_t(k));
      for (int i = 0; i < n; ++i, ++idx) {
        const double qxv = rowQ[std::size_t(i)];
        const double outside = outsideYz + (qxv > 0 ? qxv * qxv : 0);
        const double d = std::sqrt(outside) + std::min(std::max(insideYz, qxv), 0.0) - kBlockRounding;
        // Beyond the soft tissue: outside air lateral to the skin, the brain (and the soft tissue
        // of the neck) everywhere else, as around a temporal bone in a head.
        Material m = c.coord(i) < kSkinX ? kAir : kBrain;
        if (d <= -kCortexMm) m = kCancellous;
        else if (d <= 0) m = kCortical;
        else if (d <= kSoftTissueMm) m = kSoftTissue;
        (*c.material)[idx] = m;
      }
    }
}

void paintOp(const Canvas& c, const PaintOp& op, int k0, int k1) {
  for (const Shape& s : op.shapes) {
    Vec3 lo{}, hi{};
    s.bounds(lo, hi);
    int ib[2][3];
    for (int a = 0; a < 3; ++a) c.indexRange(lo[a] - op.growMm, hi[a] + op.growMm, ib[0][a], ib[1][a]);
    const int kb = std::max(ib[0][2], k0), ke = std::min(ib[1][2], k1 - 1);
    for (int k = kb; k <= ke; ++k)
      for (int j = ib[0][1]; j <= ib[1][1]; ++j) {
        const std::size_t row = std::size_t(c.n) * (std::size_t(j) + std::size_t(c.n) * std::size_t(k));
        for (int i = ib[0][0]; i <= ib[1][0]; ++i) {
          const std::size_t idx = row + std::size_t(i);
          if (!allowed(op.where, (*c.labels)[idx])) continue;
          if (s.sd({c.coord(i), c.coord(j), c.coord(k)}) > op.growMm) continue;
          (*c.material)[idx] = op.material;
          (*c.labels)[idx] = op.label;
        }
      }
  }
}

// Smooth texture in [0, 1] on a 1.5 mm lattice (fixed: part of the anatomy, not of the noise).
class BoneTexture {
 public:
  BoneTexture(double cornerMm, double extentMm) : corner_(cornerMm) {
    n_ = int(std::ceil(extentMm / kStepMm)) + 2;
    values_.resize(std::size_t(n_) * n_ * n_);
    for (std::size_t v = 0; v < values_.size(); ++v)
      values_[v] = float(double(splitmix64(kAnatomySeed ^ (v * 0xD6E8FEB86659FD93ULL)) >> 11) /
                         9007199254740992.0);
  }
  // Values along the lattice x nodes, interpolated bilinearly at (y, z): one row's worth.
  void row(double y, double z, std::vector<double>& out) const {
    int i[2];
    double f[2];
    const double p[2] = {(y - corner_) / kStepMm, (z - corner_) / kStepMm};
    for (int a = 0; a < 2; ++a) {
      const double q = std::clamp(p[a], 0.0, double(n_ - 2) - 1e-9);
      i[a] = int(q);
      f[a] = q - i[a];
    }
    out.resize(std::size_t(n_));
    for (int x = 0; x < n_; ++x) {
      double sum = 0;
      for (int dz = 0; dz < 2; ++dz)
        for (int dy = 0; dy < 2; ++dy)
          sum += (dy ? f[0] : 1 - f[0]) * (dz ? f[1] : 1 - f[1]) *
                 values_[std::size_t(x) + std::size_t(n_) * (std::size_t(i[0] + dy) + std::size_t(n_) * std::size_t(i[1] + dz))];
      out[std::size_t(x)] = sum;
    }
  }
  // Linear interpolation in x of a row from row().
  double along(const std::vector<double>& rowValues, double x) const {
    const double q = std::clamp((x - corner_) / kStepMm, 0.0, double(n_ - 2) - 1e-9);
    const int i = int(q);
    const double f = q - i;
    return rowValues[std::size_t(i)] * (1 - f) + rowValues[std::size_t(i) + 1] * f;
  }

 private:
  static constexpr double kStepMm = 1.5;
  double corner_;
  int n_ = 0;
  std::vector<float> values_;
};

// HU before the point-spread function: each material's value, the cancellous texture, and white
// noise at the amplitude that leaves kNoiseSigmaHu after the blur.
void paintHu(const Canvas& c, const BoneTexture& texture, std::uint64_t seed, double whiteSigmaHu,
             std::vector<float>& hu, int k0, int k1) {
  const std::uint64_t seedMix = splitmix64(seed ^ 0xA0761D6478BD642FULL);
  std::vector<double> textureRow;
  for (int k = k0; k < k1; ++k)
    for (int j = 0; j < c.n; ++j) {
      texture.row(c.coord(j), c.coord(k), textureRow);
      std::size_t idx = std::size_t(c.n) * (std::size_t(j) + std::size_t(c.n) * std::size_t(k));
      for (int i = 0; i < c.n; ++i, ++idx) {
        const Material m = Material((*c.material)[idx]);
        double value = materialHu(m);
        if (m == kCancellous) value += 200.0 * (texture.along(textureRow, c.coord(i)) - 0.5);
        // Irwin–Hall: four 16-bit uniforms, mean 2, variance 1/3 → unit normal-ish noise.
        const std::uint64_t h = splitmix64(seedMix + idx * 0x9E3779B97F4A7C15ULL);
        const double sum = double(h & 0xFFFF) + double((h >> 16) & 0xFFFF) + double((h >> 32) & 0xFFFF) +
                           double(h >> 48);
        const double z = (sum / 65536.0 - 2.0) * 1.7320508075688772;
        hu[idx] = float(value + whiteSigmaHu * z);
      }
    }
}

// The point-spread function: a normalised Gaussian of kPsfSigmaMm, sampled at the voxel spacing
// (a single tap on grids too coarse to resolve it).
std::vector<float> psfKernel(double spacingMm) {
  const double sigma = kPsfSigmaMm / spacingMm;
  if (sigma < 0.25) return {1.0f};
  const int radius = int(std::ceil(3.0 * sigma));
  std::vector<float> w(std::size_t(2 * radius + 1));
  double sum = 0;
  for (int i = -radius; i <= radius; ++i) sum += w[std::size_t(i + radius)] = float(std::exp(-0.5 * i * i / (sigma * sigma)));
  for (float& x : w) x = float(x / sum);
  return w;
}

// Convolves one axis of an n³ cube with `kernel` (edge-clamped), lines split over threads.
void blurAxis(std::vector<float>& v, int n, int axis, const std::vector<float>& kernel, int threads) {
  const int radius = int(kernel.size() / 2);
  const std::size_t strides[3] = {1, std::size_t(n), std::size_t(n) * std::size_t(n)};
  const std::size_t along = strides[axis];
  // Lines are indexed by the other two axes (a, b); threads take ranges of b.
  const std::size_t sa = strides[axis == 0 ? 1 : 0], sb = strides[axis == 2 ? 1 : 2];
  auto work = [&](int b0, int b1) {
    std::vector<float> line(static_cast<std::size_t>(n));
    for (int b = b0; b < b1; ++b)
      for (int a = 0; a < n; ++a) {
        const std::size_t base = std::size_t(a) * sa + std::size_t(b) * sb;
        for (int t = 0; t < n; ++t) line[std::size_t(t)] = v[base + std::size_t(t) * along];
        for (int t = 0; t < n; ++t) {
          float sum = 0;
          for (int o = -radius; o <= radius; ++o)
            sum += kernel[std::size_t(o + radius)] * line[std::size_t(std::clamp(t + o, 0, n - 1))];
          v[base + std::size_t(t) * along] = sum;
        }
      }
  };
  forEachBlockInParallel(n, work, threads);
}

Structure makeStructure(const char* id, const char* name, std::array<float, 3> colour, const char* system,
                        const char* description) {
  Structure s;
  s.id = id;
  s.displayName = name;
  s.colour = colour;
  s.system = system;
  s.description = description;
  return s;
}

}  // namespace

const std::vector<Structure>& phantomStructures() {
  static const std::vector<Structure> structures = [] {
    std::vector<Structure> list = {
        makeStructure("cochlea", "Cochlea", {1.0f, 0.55f, 0.3f}, "inner ear",
                      "The snail-shaped, fluid-filled hearing organ of the inner ear, coiled about 2.5 turns "
                      "inside the dense otic capsule; its basal turn bulges into the middle ear as the promontory."),
        makeStructure("vestibule", "Vestibule", {1.0f, 0.75f, 0.35f}, "inner ear",
                      "The central fluid-filled chamber of the bony labyrinth, holding the utricle and saccule "
                      "(sensing gravity and linear acceleration); the cochlea and all three canals open into it."),
        makeStructure("lateral_semicircular_canal", "Lateral semicircular canal", {1.0f, 0.45f, 0.55f}, "inner ear",
                      "The roughly horizontal semicircular canal, sensing head rotation about a vertical axis; "
                      "it bulges into the medial wall of the middle ear just above the facial nerve."),
        makeStructure("posterior_semicircular_canal", "Posterior semicircular canal", {0.85f, 0.35f, 0.75f},
                      "inner ear",
                      "A vertical semicircular canal lying parallel to the long axis of the petrous bone, "
                      "the lowest and most posterior of the three canals."),
        makeStructure("superior_semicircular_canal", "Superior semicircular canal", {1.0f, 0.6f, 0.85f},
                      "inner ear",
                      "A vertical semicircular canal perpendicular to the long axis of the petrous bone, "
                      "arching highest of the three canals just beneath the middle cranial fossa."),
        makeStructure("facial_nerve", "Facial nerve", {1.0f, 0.9f, 0.1f}, "nerves",
                      "Cranial nerve VII runs through the temporal bone in its own bony (fallopian) canal: "
                      "labyrinthine segment to the geniculate ganglion, tympanic segment along the middle ear, "
                      "and mastoid segment down to the stylomastoid foramen."),
        makeStructure("internal_auditory_canal", "Internal auditory canal", {0.45f, 0.85f, 0.75f}, "nerves",
                      "A CSF-filled canal running from the posterior cranial fossa to the inner ear, carrying the "
                      "facial and vestibulocochlear nerves and the labyrinthine artery."),
        makeStructure("external_auditory_canal", "External auditory canal", {0.55f, 0.75f, 1.0f}, "external ear",
                      "The air-filled canal leading from the outer ear to the tympanic membrane; its inner part "
                      "is surrounded by bone."),
        makeStructure("tympanic_cavity", "Tympanic cavity", {0.3f, 0.55f, 0.95f}, "middle ear",
                      "The air-filled middle ear between the tympanic membrane and the inner ear, housing the "
                      "three ossicles; the oval window at its medial wall leads to the vestibule."),
        makeStructure("malleus", "Malleus", {0.95f, 0.92f, 0.72f}, "middle ear",
                      "The hammer-shaped outermost ossicle: its handle is attached to the tympanic membrane and "
                      "its head articulates with the incus in the upper middle ear."),
        makeStructure("incus", "Incus", {0.8f, 0.65f, 0.45f}, "middle ear",
                      "The anvil-shaped middle ossicle, passing vibrations from the malleus to the stapes "
                      "through its long process."),
        makeStructure("stapes", "Stapes", {0.55f, 0.85f, 0.45f}, "middle ear",
                      "The stirrup-shaped innermost ossicle, the smallest bone of the body; its footplate sits "
                      "in the oval window and moves the fluid of the vestibule."),
        makeStructure("mastoid_air_cells", "Mastoid air cells", {0.7f, 0.7f, 0.95f}, "middle ear",
                      "Air-filled cavities in the mastoid part of the temporal bone, connected to the middle ear "
                      "through the antrum; their extent varies widely between people."),
        makeStructure("sigmoid_sinus", "Sigmoid sinus", {0.2f, 0.35f, 0.9f}, "vessels",
                      "An S-shaped dural venous sinus grooving the inner surface of the mastoid, draining blood "
                      "from the transverse sinus to the internal jugular vein."),
        makeStructure("carotid_canal", "Carotid canal", {0.9f, 0.15f, 0.15f}, "vessels",
                      "The bony canal of the internal carotid artery, ascending in front of the cochlea and then "
                      "turning forwards and medially towards the petrous apex."),
        makeStructure("temporal_line", "Temporal line", {0.65f, 0.45f, 0.25f}, "landmarks",
                      "A ridge on the outer surface of the temporal bone above the external auditory canal, "
                      "marking roughly the floor of the middle cranial fossa; a surgical landmark for the mastoid."),
    };
    for (std::size_t i = 0; i < list.size(); ++i) list[i].label = std::uint16_t(i + 1);
    return list;
  }();
  return structures;
}

Dataset makePhantom(const PhantomOptions& options) {
  assert(options.size >= 1 && options.extentMm > 0 && "makePhantom: size and extent must be positive");
  const int n = options.size;
  const double spacing = options.extentMm / n;

  Geometry g;
  g.dims = {n, n, n};
  g.spacingMm = {spacing, spacing, spacing};
  const double origin = -options.extentMm / 2 + spacing / 2;
  g.originMm = {origin, origin, origin};

  Dataset ds;
  ds.id = n == 256 ? "phantom" : "phantom:" + std::to_string(n);
  ds.displayName = "Temporal-bone phantom (synthetic)";
  ds.volume = Volume(g, 0);
  ds.labels = LabelMap(g, 0);
  ds.structures = phantomStructures();
  char spacingText[32];
  std::snprintf(spacingText, sizeof spacingText, "%.3g", spacing);
  ds.provenance.source = "synthetic temporal-bone phantom (seed " + std::to_string(options.seed) + ", " +
                         std::to_string(n) + "^3, " + spacingText + " mm voxels)";
  ds.provenance.notes.push_back(
      "synthetic: analytic shapes at plausible positions of a right temporal bone (lateral = -x), "
      "not a scan of anyone");

  const Anatomy anatomy = buildAnatomy(spacing);
  const BoneTexture texture(-options.extentMm / 2, options.extentMm);
  std::vector<std::uint8_t> material(g.dims.count(), kAir);
  Canvas canvas;
  canvas.n = n;
  canvas.spacing = spacing;
  canvas.origin = origin;
  canvas.material = &material;
  canvas.labels = &ds.labels.voxels;

  const std::vector<float> kernel = psfKernel(spacing);
  double kernelEnergy = 0;
  for (float w : kernel) kernelEnergy += double(w) * double(w);
  const double whiteSigmaHu = kNoiseSigmaHu / std::pow(kernelEnergy, 1.5);
  std::vector<float> hu(g.dims.count());
  auto work = [&](int k0, int k1) {
    paintBase(canvas, k0, k1);
    for (const PaintOp& op : anatomy.ops) paintOp(canvas, op, k0, k1);
    paintHu(canvas, texture, options.seed, whiteSigmaHu, hu, k0, k1);
  };
  const int threads = std::clamp(int(std::thread::hardware_concurrency()), 1, std::min(16, n));
  forEachBlockInParallel(n, work, threads);
  if (kernel.size() > 1)
    for (int axis = 0; axis < 3; ++axis) blurAxis(hu, n, axis, kernel, threads);
  for (std::size_t v = 0; v < hu.size(); ++v)
    ds.volume.voxels[v] = std::int16_t(std::floor(std::clamp(double(hu[v]), -1024.0, 3071.0) + 0.5));
  return ds;
}

}  // namespace at
