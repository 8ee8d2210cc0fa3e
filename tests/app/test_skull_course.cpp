// The skull course on the real head CT (scripts/fetch-scans.sh), with its labels grown from the
// seeds kept in data/segmentations/skull/ (tests/support/skull_scan.h): the labels come out bit for
// bit as reviewed, every structure is big enough and lies where the anatomy puts it, and every
// structure's context and bare presets render it visibly. Skipped, with a line saying so, where the
// Debian package could not be fetched.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <sys/wait.h>
#include <fstream>
#include <functional>
#include <map>

#include <nlohmann/json.hpp>

#include "course_wording.h"
#include "dataset_resolver.h"
#include "lessons/course_json.h"
#include "render/scene.h"
#include "scan_catalogue.h"
#include "segment/seeds.h"
#include "skull_scan.h"
#include "test_support.h"
#include "volume/png_image.h"
#include "wdt/answer_keys.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

Dataset openSkull() {
  app::DatasetRequest request;
  request.name = "skull";
  auto dataset = app::openNamedDataset(request);
  REQUIRE_MESSAGE(dataset, test::errorText(dataset));
  return std::move(*dataset);
}

std::uint64_t fnv1a64(const std::vector<std::uint16_t>& voxels) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (std::uint16_t v : voxels)
    for (std::uint8_t byte : {std::uint8_t(v & 0xff), std::uint8_t(v >> 8)}) {
      h ^= byte;
      h *= 0x100000001b3ull;
    }
  return h;
}

struct Centroid {
  Vec3 mm{0, 0, 0};
  std::size_t voxels = 0;
};

std::map<std::uint16_t, Centroid> centroids(const LabelMap& labels) {
  std::map<std::uint16_t, Centroid> out;
  const Dims& d = labels.dims();
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (const std::uint16_t l = labels.at(i, j, k)) {
          Centroid& c = out[l];
          c.mm = c.mm + labels.geometry.indexToPatient({double(i), double(j), double(k)});
          ++c.voxels;
        }
  for (auto& [label, c] : out) c.mm = (1.0 / double(c.voxels)) * c.mm;
  return out;
}

// Where each structure lies, in the loader's LPS millimetres centred on the scan (x toward the
// patient's left, y toward posterior, z toward superior; the ear canals at z ≈ -47): first-year
// anatomy, with margins of a centimetre or more.
const std::map<std::string, std::function<bool(const Vec3&)>>& expectedPlaces() {
  static const std::map<std::string, std::function<bool(const Vec3&)>> places = {
      {"upper_teeth", [](const Vec3& p) { return p[2] < -65 && p[1] < -40; }},             // lowest, in front
      {"mandible", [](const Vec3& p) { return p[2] < -55 && p[1] < 0; }},                  // inferior, anterior
      {"maxilla", [](const Vec3& p) { return p[2] < -45 && p[1] < -40; }},
      {"zygomatic_arch_right", [](const Vec3& p) { return p[0] < -45 && p[2] > -60 && p[2] < -30; }},
      {"zygomatic_arch_left", [](const Vec3& p) { return p[0] > 45 && p[2] > -60 && p[2] < -30; }},
      {"nasal_cavity", [](const Vec3& p) { return p[1] < -25 && p[2] < -30; }},
      {"maxillary_sinus_right", [](const Vec3& p) { return p[0] < -12 && p[1] < -30 && p[2] < -25; }},
      {"maxillary_sinus_left", [](const Vec3& p) { return p[0] > 12 && p[1] < -30 && p[2] < -25; }},
      {"frontal_sinus", [](const Vec3& p) { return p[1] < -55 && p[2] > -10; }},          // highest sinus, in front
      {"sphenoid_sinus", [](const Vec3& p) { return p[1] > -35 && p[1] < 0 && p[2] < -20; }},  // behind the nose
      {"ethmoid_air_cells", [](const Vec3& p) { return p[1] < -25 && p[2] > -40 && p[2] < -10; }},  // between the orbits
      {"orbit_right", [](const Vec3& p) { return p[0] < -20 && p[1] < -35 && p[2] > -40 && p[2] < 0; }},
      {"orbit_left", [](const Vec3& p) { return p[0] > 20 && p[1] < -35 && p[2] > -40 && p[2] < 0; }},
      {"external_acoustic_meatus_right", [](const Vec3& p) { return p[0] < -40 && p[1] > -5 && p[1] < 25; }},
      {"external_acoustic_meatus_left", [](const Vec3& p) { return p[0] > 40 && p[1] > -5 && p[1] < 25; }},
      {"mastoid_air_cells_right", [](const Vec3& p) { return p[0] < -35 && p[1] > 10; }},  // posterior-lateral
      {"mastoid_air_cells_left", [](const Vec3& p) { return p[0] > 35 && p[1] > 10; }},
      {"petrous_temporal_bone_right", [](const Vec3& p) { return p[0] < -20 && p[0] > -55 && p[1] > 0; }},
      {"petrous_temporal_bone_left", [](const Vec3& p) { return p[0] > 20 && p[0] < 55 && p[1] > 0; }},
      {"atlas_c1", [](const Vec3& p) { return p[1] > 0 && p[2] < -65; }},                  // behind the teeth, lowest
      {"axis_c2", [](const Vec3& p) { return p[1] > 0 && p[2] < -65; }},
      // Above the notch (k 17 and up) under the zygomatic arch, in front of the condyles.
      {"coronoid_process_right", [](const Vec3& p) { return p[0] < -30 && p[1] < -20 && p[2] > -60 && p[2] < -40; }},
      {"coronoid_process_left", [](const Vec3& p) { return p[0] > 30 && p[1] < -20 && p[2] > -60 && p[2] < -40; }},
      // On the left side of the vault, above the zygomatic arch (whose level is z ≈ -45).
      {"temporal_line_left", [](const Vec3& p) { return p[0] > 45 && p[2] > -20; }},
  };
  return places;
}

// Pixels in the highlight's orange (red well above blue; the bone context is grey-beige).
int highlightPixels(const RgbImage& image) {
  int n = 0;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const std::uint8_t* p = image.pixel(x, y);
      if (p[0] > 150 && p[0] > p[2] + 90) ++n;
    }
  return n;
}

}  // namespace

TEST_CASE("The skull's labels grow bit for bit from the kept seeds, as reviewed") {
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::SkullCacheScope scope(*cache);
  const Dataset skull = openSkull();
  const auto reference = nlohmann::json::parse(test::readFile(test::sourceDir() / "data" / "segmentations" / "skull" /
                                                              "labels.reference.json"));
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a64(skull.labels.voxels)));
  CHECK(std::string(hash) == reference.at("fnv1a64").get<std::string>());
  const auto found = centroids(skull.labels);
  CHECK(skull.structures.size() == reference.at("voxels").size());
  for (const Structure& s : skull.structures) {
    CAPTURE(s.displayName);
    REQUIRE(reference.at("voxels").contains(s.displayName));
    CHECK(found.at(s.label).voxels == reference.at("voxels").at(s.displayName).get<std::size_t>());
  }
}

TEST_CASE("Every skull label with a grow_range in its seeds lies in that range: bones are bone, canals air") {
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::SkullCacheScope scope(*cache);
  const Dataset skull = openSkull();
  auto seeds = segment::loadSeeds(test::sourceDir() / "data" / "segmentations" / "skull" / "seeds.json");
  REQUIRE_MESSAGE(seeds, test::errorText(seeds));
  int ranged = 0;
  for (const segment::SeedLabel& l : seeds->labels) {
    if (!l.growRange) continue;  // the skull's ranges are explicit HU ranges
    CAPTURE(l.name);
    ++ranged;
    std::size_t voxels = 0, outside = 0;
    for (std::size_t i = 0; i < skull.labels.voxels.size(); ++i) {
      if (skull.labels.voxels[i] != l.value) continue;
      ++voxels;
      const double hu = skull.intensity.valueOf(skull.volume.voxels[i]);
      outside += hu < (*l.growRange)[0] || hu > (*l.growRange)[1];
    }
    CHECK(voxels >= 100);
    CHECK(outside == 0);
  }
  CHECK(ranged >= 10);  // the bones (mandible, coronoid processes, maxilla, arches, C1, C2) and both canals
}

TEST_CASE("Every skull structure is described, has at least 100 voxels and lies where the anatomy puts it") {
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::SkullCacheScope scope(*cache);
  const Dataset skull = openSkull();
  auto catalogue = app::loadStructureCatalogue(test::sourceDir() / "data" / "segmentations" / "skull" / "structures.json");
  REQUIRE_MESSAGE(catalogue, test::errorText(catalogue));
  CHECK(skull.structures.size() >= 16);
  CHECK(skull.structures.size() == catalogue->structures.size());
  const auto found = centroids(skull.labels);
  for (const Structure& s : skull.structures) {
    CAPTURE(s.id);
    const Centroid& c = found.at(s.label);
    const std::string where = "(" + std::to_string(c.mm[0]) + ", " + std::to_string(c.mm[1]) + ", " + std::to_string(c.mm[2]) + ") mm";
    CAPTURE(where);
    CHECK(c.voxels >= 100);
    CHECK(!s.description.empty());
    CHECK(!s.system.empty());
    auto entry = std::find_if(catalogue->structures.begin(), catalogue->structures.end(),
                              [&](const app::CatalogueEntry& e) { return e.id == s.id; });
    REQUIRE(entry != catalogue->structures.end());
    // Sides: the loader's +x is the patient's left (docs/skull_landmarks.md).
    if (entry->side == "left") CHECK(c.mm[0] > 10);
    if (entry->side == "right") CHECK(c.mm[0] < -10);
    if (entry->side == "midline") CHECK(std::abs(c.mm[0]) < 10);
    CHECK((s.id.find("_left") != std::string::npos) == (entry->side == "left"));
    CHECK((s.id.find("_right") != std::string::npos) == (entry->side == "right"));
    REQUIRE(expectedPlaces().count(s.id));
    CHECK(expectedPlaces().at(s.id)(c.mm));
  }
  // Relative places: the mandible below and in front of the mastoids, the teeth below the orbits.
  const auto centre = [&](const std::string& id) { return found.at(skull.findStructure(id)->label).mm; };
  CHECK(centre("mandible")[2] < centre("mastoid_air_cells_right")[2]);
  CHECK(centre("mandible")[1] < centre("mastoid_air_cells_left")[1] - 20);
  // Each coronoid process above the rest of the mandible and in front of it.
  for (const char* coronoid : {"coronoid_process_right", "coronoid_process_left"}) {
    CHECK(centre(coronoid)[2] > centre("mandible")[2] + 10);
    CHECK(centre(coronoid)[1] < centre("mandible")[1] - 5);
  }
  CHECK(centre("upper_teeth")[2] < centre("orbit_left")[2] - 30);
  CHECK(centre("frontal_sinus")[2] > centre("ethmoid_air_cells")[2]);
  CHECK(centre("ethmoid_air_cells")[1] < centre("sphenoid_sinus")[1]);
}

// An orbit is the socket of bone closed in front by its opening (the rim from the nose to the
// cheekbone): it does not take the eyelids or the skin of the brow and cheek in front of the rim.
// Measured as its voxels within 2 voxels in-plane and 1 slice of the air seen from the front (air
// with no tissue between it and the grid's front face): 15.6 % of each when the labels ran out to
// the skin, about 1 % behind the opening.
TEST_CASE("Each skull orbit ends at its bony opening: it does not reach the air in front of the face") {
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::SkullCacheScope scope(*cache);
  const Dataset skull = openSkull();
  const Dims& d = skull.volume.dims();
  // The voxel axis that runs toward the patient's front (LPS: anterior is -y), and its sign.
  const Geometry& g = skull.labels.geometry;
  const Vec3 origin = g.indexToPatient({0, 0, 0});
  int axis = 0;
  double towardFront = 0;
  for (int a = 0; a < 3; ++a) {
    Vec3 step{0, 0, 0};
    step[a] = 1;
    const double dy = g.indexToPatient(step)[1] - origin[1];
    if (std::abs(dy) > std::abs(towardFront)) axis = a, towardFront = dy;
  }
  REQUIRE(axis == 1);  // the scan is axial: j runs front to back
  const int frontStep = towardFront < 0 ? 1 : -1;
  const auto index = [&](int i, int j, int k) { return (std::size_t(k) * d.y + std::size_t(j)) * d.x + std::size_t(i); };
  std::vector<char> frontAir(skull.volume.voxels.size(), 0);
  for (int k = 0; k < d.z; ++k)
    for (int i = 0; i < d.x; ++i) {
      bool open = true;  // no tissue yet, coming in from the front face
      for (int n = 0; n < d.y; ++n) {
        const int j = frontStep > 0 ? d.y - 1 - n : n;
        open = open && skull.intensity.valueOf(skull.volume.voxels[index(i, j, k)]) < -400;
        frontAir[index(i, j, k)] = open;
      }
    }
  for (const char* id : {"orbit_right", "orbit_left"}) {
    CAPTURE(id);
    const Structure* orbit = skull.findStructure(id);
    REQUIRE(orbit);
    std::size_t voxels = 0, atTheFace = 0;
    for (int k = 0; k < d.z; ++k)
      for (int j = 0; j < d.y; ++j)
        for (int i = 0; i < d.x; ++i) {
          if (skull.labels.voxels[index(i, j, k)] != orbit->label) continue;
          ++voxels;
          bool near = false;
          for (int dk = -1; dk <= 1 && !near; ++dk)
            for (int dj = -2; dj <= 2 && !near; ++dj)
              for (int di = -2; di <= 2 && !near; ++di) {
                const int x = i + di, y = j + dj, z = k + dk;
                near = x >= 0 && y >= 0 && z >= 0 && x < d.x && y < d.y && z < d.z && frontAir[index(x, y, z)];
              }
          atTheFace += near;
        }
    MESSAGE(std::string(id) << ": " << atTheFace << " of " << voxels << " voxels next to the air in front of the face");
    CHECK(voxels >= 5000);
    CHECK(double(atTheFace) <= 0.03 * double(voxels));
  }
}

TEST_CASE("Every skull structure's context (WDT) and bare presets render it visibly") {
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  if (!test::requireAppBinary("rendering the skull's presets")) return;
  test::SkullCacheScope scope(*cache);
  const Dataset skull = openSkull();
  test::TempDir dir("skull-presets");
  for (const Structure& s : skull.structures)
    for (const char* mode : {"wdt", "bare"}) {
      CAPTURE(s.id);
      CAPTURE(mode);
      const fs::path png = dir / (s.id + "_" + mode + ".png");
      const auto r = test::runApp("render skull " + s.id + " --mode " + mode + " --size 120x90 --no-overlays --out '" +
                                  png.string() + "'");
      REQUIRE_MESSAGE(r.exitCode == 0, r.err);
      auto image = readPng(png.string());
      REQUIRE(image);
      CHECK(highlightPixels(*image) >= 60);  // of 10,800
    }
}

TEST_CASE("anatomy-tutor --course skull with no display writes the skull course's first views") {
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::TempDir dir("skull-first-views");
  const fs::path out = dir / "stdout", err = dir / "stderr";
  const std::string cmd = "cd '" + dir.path().string() + "' && env -u DISPLAY -u WAYLAND_DISPLAY XDG_CACHE_HOME='" +
                          cache->string() + "' '" + test::appBinary().string() + "' --course skull >'" + out.string() +
                          "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  const std::string text = test::readFile(out);
  INFO(text << test::readFile(err));
  REQUIRE(WIFEXITED(status));
  if (WEXITSTATUS(status) != 0 && test::readFile(err).find("offscreen rendering") != std::string::npos) {
    at::test::skipf("the skull course's first views need an EGL offscreen context");
    return;
  }
  REQUIRE(WEXITSTATUS(status) == 0);
  CHECK(text.rfind("anatomy-tutor: no display", 0) == 0);
  CHECK(text.find("'skull' course") != std::string::npos);
  // The first lesson's first three show steps: the maxilla, the upper teeth, the mandible.
  for (const char* name : {"01_maxilla_wdt.png", "02_upper_teeth_bare.png", "03_mandible_wdt.png"}) {
    CAPTURE(name);
    auto image = readPng((dir / "anatomy-tutor-views" / name).string());
    REQUIRE(image);
    CHECK(highlightPixels(*image) > image->width * image->height / 50);
  }
  const auto unknown = test::runApp("--course no_such_course");
  CHECK(unknown.exitCode != 0);
  CHECK(unknown.err.find("no course 'no_such_course'") != std::string::npos);
}

TEST_CASE("The skull course's texts pass the phantom course's wording checks: names mid-sentence, no program jargon") {
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::SkullCacheScope scope(*cache);
  const Dataset skull = openSkull();
  auto course = lessons::loadCourseJson(test::sourceDir() / "data" / "courses" / "skull.json");
  REQUIRE_MESSAGE(course, (course ? "" : course.error().message));
  quiz::DatasetKeyComputer keys(skull, [&skull](const Mask& seeds) {
    return wdt::answerKeyDistances(skull.volume, skull.labels.geometry, seeds);
  });
  const int texts = test::checkCourseWording(*course, skull.structures, keys);
  CHECK(texts > 60);
  MESSAGE(texts << " texts of the skull course read");
}

TEST_CASE("Every skull label's review is recorded: completed, or flagged with what is off") {
  auto catalogue = app::loadStructureCatalogue(test::sourceDir() / "data" / "segmentations" / "skull" / "structures.json");
  REQUIRE_MESSAGE(catalogue, test::errorText(catalogue));
  int completed = 0, flagged = 0;
  for (const app::CatalogueEntry& e : catalogue->structures) {
    CAPTURE(e.id);
    // What was looked at: slices and the 3-D render (docs/skull_labels_review.png).
    CHECK(e.review.find("slices") != std::string::npos);
    CHECK(e.review.find("3-D") != std::string::npos);
    if (e.reviewState == "completed") ++completed;
    if (e.reviewState == "flagged") ++flagged;
  }
  CHECK(completed + flagged == int(catalogue->structures.size()));
  // A catalogue with another state is refused, naming the file and the field.
  test::TempDir dir("skull-catalogue");
  auto text = test::readFile(test::sourceDir() / "data" / "segmentations" / "skull" / "structures.json");
  const std::string state = "\"review_state\": \"completed\"";
  const auto at = text.find(state);
  REQUIRE(at != std::string::npos);
  text.replace(at, state.size(), "\"review_state\": \"looks fine\"");
  const fs::path bad = dir / "structures.json";
  std::ofstream(bad) << text;
  auto refused = app::loadStructureCatalogue(bad);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find(bad.string()) != std::string::npos);
  CHECK(refused.error().message.find("review_state: must be completed or flagged, not 'looks fine'") != std::string::npos);
}
