// The segment editor's sphere brush on the 3-D view (Xvfb): with the paint tool, a click in the
// view paints the current structure in a ball of the brush's radius around the point where the
// ray meets the volume — in mm on an anisotropic grid, exactly the voxels within the radius and
// only those; erase takes a smaller ball out of it; undo and redo bring back each state.
#include <doctest/doctest.h>

#include <cmath>
#include <set>

#include "box_volume.h"
#include "desktop_script.h"
#include "test_support.h"
#include "volume/nifti_io.h"

using namespace at;
using test::kBoxHi;
using test::kBoxLo;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

constexpr int kDesktopPanel = 320;  // the explore panel at UI scale 1 (the view lies right of it)

Vec3 pointOf(const json& event) {
  const auto p = event.at("point_mm").get<std::vector<double>>();
  REQUIRE(p.size() == 3);
  return {p[0], p[1], p[2]};
}

// Voxels of `labels` equal to `value`.
std::set<std::size_t> voxelsOf(const FloatVolume& labels, float value) {
  std::set<std::size_t> out;
  for (std::size_t i = 0; i < labels.voxels.size(); ++i)
    if (labels.voxels[i] == value) out.insert(i);
  return out;
}

// The voxels whose centres lie within `radius` mm of `centre` (the brush's ball), with the voxel
// nearest the centre; `ambiguous` gets those within 1e-6 mm of the sphere (either way is right).
std::set<std::size_t> ball(const Geometry& g, const Vec3& centre, double radius, std::set<std::size_t>& ambiguous) {
  std::set<std::size_t> out;
  for (int k = 0; k < g.dims.z; ++k)
    for (int j = 0; j < g.dims.y; ++j)
      for (int i = 0; i < g.dims.x; ++i) {
        const double d = norm(g.indexToPatient({double(i), double(j), double(k)}) - centre);
        if (std::abs(d - radius) < 1e-6) ambiguous.insert(g.dims.index(i, j, k));
        else if (d < radius) out.insert(g.dims.index(i, j, k));
      }
  const Vec3 ijk = g.patientToIndex(centre);
  out.insert(g.dims.index(int(std::lround(ijk[0])), int(std::lround(ijk[1])), int(std::lround(ijk[2]))));
  return out;
}

// `got` equals `want` apart from voxels in `ambiguous`.
void checkSameVoxels(const std::set<std::size_t>& got, const std::set<std::size_t>& want,
                     const std::set<std::size_t>& ambiguous) {
  std::size_t extra = 0, missing = 0;
  for (std::size_t v : got) extra += !want.count(v) && !ambiguous.count(v);
  for (std::size_t v : want) missing += !got.count(v);
  CAPTURE(got.size());
  CAPTURE(want.size());
  CHECK(extra == 0);
  CHECK(missing == 0);
}

}  // namespace

TEST_CASE("desktop: the paint brush on the 3-D surface labels the voxels within its radius in mm, and only those") {
  if (!test::requireXvfb()) return;
  test::TempDir dir;
  const fs::path box = test::writeBox(dir);
  const fs::path painted = dir / "painted.nii.gz", erased = dir / "erased.nii.gz", undone = dir / "undone.nii.gz",
                 redone = dir / "redone.nii.gz";
  const int cx = kDesktopPanel + (800 - kDesktopPanel) / 2, cy = 240;
  const json script = {
      {"actions",
       {{{"do", "view"}, {"value", "anterior"}},
        {{"do", "segment_open"}},
        {{"do", "segment_label"}, {"name", "patch"}},
        {{"do", "segment_tool"}, {"tool", "paint"}, {"brush_mm", 3.0}},
        {{"do", "click"}, {"x", cx}, {"y", cy}},
        {{"do", "segment_save"}, {"out", painted.string()}},
        {{"do", "segment_tool"}, {"tool", "erase"}, {"brush_mm", 1.7}},
        {{"do", "click"}, {"x", cx}, {"y", cy}},
        {{"do", "segment_save"}, {"out", erased.string()}},
        {{"do", "segment_undo"}},
        {{"do", "segment_save"}, {"out", undone.string()}},
        {{"do", "segment_redo"}},
        {{"do", "segment_save"}, {"out", redone.string()}},
        {{"do", "segment_tool"}, {"tool", "seeds"}},
        {{"do", "click"}, {"x", cx}, {"y", cy}}}}};  // seeds: a click in the view paints nothing
  test::DesktopOptions options;
  options.dataset = box.string();
  const auto run = test::runDesktopScript(dir, script, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  const auto edits = test::eventsOf(run.events, "segment_edited");
  REQUIRE(edits.size() == 2);
  CHECK(edits[0]["tool"] == "paint");
  CHECK(edits[1]["tool"] == "erase");
  CHECK(edits[0]["radius_mm"].get<double>() == doctest::Approx(3.0));

  auto paintedMap = loadNifti(painted.string());
  REQUIRE_MESSAGE(paintedMap, test::errorText(paintedMap));
  const Geometry& g = paintedMap->image.geometry;
  CHECK(g.spacingMm[2] == doctest::Approx(2.0));
  // The ray met the box's front: the point lies on its surface (within a voxel), not in the air.
  const Vec3 p = pointOf(edits[0]), ijk = g.patientToIndex(p);
  CAPTURE(ijk[0]);
  CAPTURE(ijk[1]);
  CAPTURE(ijk[2]);
  double nearestFace = 1e9;
  for (int a = 0; a < 3; ++a) {
    CHECK(ijk[a] >= kBoxLo[a] - 1.0);
    CHECK(ijk[a] <= kBoxHi[a] + 1.0);
    nearestFace = std::min({nearestFace, std::abs(ijk[a] - (kBoxLo[a] - 0.5)), std::abs(ijk[a] - (kBoxHi[a] + 0.5))});
  }
  CHECK(nearestFace <= 1.0);

  // Painted: the ball of 3 mm around the point — about 3.75 voxels across x and y, 1.5 along z.
  const std::set<std::size_t> paint = voxelsOf(paintedMap->image, 1.0f);
  CHECK(paint.size() == edits[0]["changed"].get<std::size_t>());
  std::set<std::size_t> ambiguous;
  const std::set<std::size_t> want = ball(g, p, 3.0, ambiguous);
  checkSameVoxels(paint, want, ambiguous);
  CHECK(voxelsOf(paintedMap->image, 0.0f).size() == g.dims.count() - paint.size());  // nothing else

  // Erased: the ball of 1.7 mm around its own pick taken out of the patch, nothing else touched.
  auto erasedMap = loadNifti(erased.string());
  REQUIRE(erasedMap);
  std::set<std::size_t> ambiguousErase;
  const std::set<std::size_t> hole = ball(g, pointOf(edits[1]), 1.7, ambiguousErase);
  std::set<std::size_t> left;
  for (std::size_t v : paint)
    if (!hole.count(v)) left.insert(v);
  ambiguousErase.insert(ambiguous.begin(), ambiguous.end());
  checkSameVoxels(voxelsOf(erasedMap->image, 1.0f), left, ambiguousErase);
  CHECK(voxelsOf(erasedMap->image, 1.0f).size() < paint.size());

  // Undo gives the painted labels back, redo the erased ones, voxel for voxel.
  auto undoneMap = loadNifti(undone.string()), redoneMap = loadNifti(redone.string());
  REQUIRE(undoneMap);
  REQUIRE(redoneMap);
  CHECK(undoneMap->image.voxels == paintedMap->image.voxels);
  CHECK(redoneMap->image.voxels == erasedMap->image.voxels);
}
