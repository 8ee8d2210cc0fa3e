// An outside check of the trapezoid rule: scikit-image's MCP_Geometric charges a step a → b
// ½(c(a) + c(b))·|step| (its docs: route_through_array([[1,3],[10,12]]) axial path costs
// ½(1+3) + ½(3+12) = 9.5), the cost of our `trapezoid` rule. Runs only where python3 has skimage.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "test_support.h"
#include "wdt/problem.h"
#include "wdt/stencil.h"
#include "wdt/wdt.h"

using namespace at;

namespace {
// Debian's python3-skimage installs for the system interpreter; a python3 earlier on PATH (pyenv,
// a virtualenv) may not see it, so the system one is tried first.
std::string pythonWithSkimage() {
  for (const char* python : {"/usr/bin/python3", "python3"}) {
    const std::string probe = std::string(python) + " -c 'import skimage.graph' >/dev/null 2>&1";
    if (std::system(probe.c_str()) == 0) return python;
  }
  return {};
}
}  // namespace

TEST_CASE("Trapezoid converged field equals skimage MCP_Geometric (fully connected)") {
  const std::string python = pythonWithSkimage();
  if (python.empty()) {
    at::test::skipf("python3 with scikit-image (skimage) is not installed");
    return;
  }
  std::mt19937_64 rng(test::freshSeed("skimage MCP_Geometric"));
  Geometry g;
  g.dims = {13, 11, 9};
  Volume v(g);
  std::uniform_int_distribution<int> hu(-1000, 2000);
  for (auto& h : v.voxels) h = std::int16_t(hu(rng));
  Mask m(g, 0);
  m.at(3, 4, 5) = 1;
  m.at(10, 2, 1) = 1;
  WdtParams p;
  p.backend = WdtBackend::Cpu;
  p.rule = StepRule::Trapezoid;
  p.converge = true;
  auto r = computeWdt(v, m, p);
  REQUIRE(r);
  auto problem = prepareWdtProblem(v, m, p);
  REQUIRE(problem);

  test::TempDir dir("at-skimage");
  {
    std::ofstream costs(dir / "costs.txt");
    for (std::uint8_t q : problem->density) costs << double(wdt::densityWeight(q, p.baseCost)) << "\n";
  }
  const std::string script = (dir / "mcp.py").string(), out = (dir / "out.txt").string();
  {
    std::ofstream py(script);
    py << "import numpy as np\nfrom skimage.graph import MCP_Geometric\n"
       << "c = np.loadtxt('" << (dir / "costs.txt").string() << "').reshape((" << g.dims.z << "," << g.dims.y << ","
       << g.dims.x << "))\n"
       << "mcp = MCP_Geometric(c, fully_connected=True)\n"
       << "cum, _ = mcp.find_costs([(5, 4, 3), (1, 2, 10)])\n"
       << "np.savetxt('" << out << "', cum.reshape(-1))\n";
  }
  REQUIRE(std::system((python + " " + script).c_str()) == 0);
  std::ifstream in(out);
  std::vector<double> expected;
  for (double x; in >> x;) expected.push_back(x);
  REQUIRE(expected.size() == r->field.distances.voxels.size());
  double worst = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (expected[i] == 0) {
      CHECK(r->field.distances.voxels[i] == 0.0f);
      continue;
    }
    worst = std::max(worst, std::abs(r->field.distances.voxels[i] - expected[i]) / expected[i]);
  }
  CHECK(worst <= 1e-5);
}
