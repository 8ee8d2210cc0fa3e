#include "render_scenes.h"

#include <cstdio>
#include <cstdlib>
#include <functional>

#include "render/scene.h"
#include "volume/mask.h"
#include "wdt/wdt.h"

namespace at::test {

namespace {

Dataset makeScene(int n, const std::function<void(const Vec3&, std::int16_t&, std::uint16_t&)>& fill) {
  Geometry g;
  g.dims = {n, n, n};
  g.spacingMm = {0.5, 0.5, 0.5};
  const double o = -0.5 * (n - 1) * 0.5;
  g.originMm = {o, o, o};
  Dataset d;
  d.id = "scene";
  d.volume = Volume(g, 0);
  d.labels = LabelMap(g, 0);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        fill(g.indexToPatient({double(i), double(j), double(k)}), d.volume.at(i, j, k), d.labels.at(i, j, k));
  return d;
}

FloatVolume field(const Dataset& d, WeightRule weight) {
  WdtParams p;
  p.weight = weight;
  p.converge = true;
  p.backend = WdtBackend::Cpu;
  auto r = computeWdt(d.volume, structureMask(d.labels, 1), p);
  if (!r) {
    std::fprintf(stderr, "render_scenes: computeWdt failed: %s\n", r.error().message.c_str());
    std::abort();
  }
  return upsampleField(r->field, d.volume.geometry);
}

Scene finish(Dataset d) {
  Scene s;
  s.weighted = field(d, WeightRule::Density);
  s.uniform = field(d, WeightRule::Uniform);
  s.dataset = std::move(d);
  return s;
}

}  // namespace

const Scene& chambersScene() {
  static const Scene scene = finish(makeScene(48, [](const Vec3& p, std::int16_t& hu, std::uint16_t& label) {
    hu = 40;
    label = 0;
    const auto inBall = [&](double cx) { return norm(p - Vec3{cx, 0, 0}) <= 2.0; };
    if (p[0] >= 3 && p[0] <= 5) hu = 1800;
    if (inBall(0)) { hu = 0; label = 1; }
    if (inBall(7)) { hu = 0; label = 2; }
    if (inBall(-7)) { hu = 0; label = 3; }
  }));
  return scene;
}

const Scene& surfaceScene() {
  static const Scene scene = finish(makeScene(40, [](const Vec3& p, std::int16_t& hu, std::uint16_t& label) {
    hu = p[2] < 0 ? 1500 : 40;
    label = 0;
    if (p[2] < 0 && p[2] > -1.0 && p[0] * p[0] + p[1] * p[1] <= 1.5 * 1.5) label = 1;
  }));
  return scene;
}

}  // namespace at::test
