// wdt/'s field service: fields equal computeWdt's, latest-wins with cancellation, an LRU cache,
// and the answer-key recipe sampled at one point equal to the upsampled field there.
#include <doctest/doctest.h>

#include <chrono>
#include <cmath>
#include <map>
#include <random>
#include <thread>

#include "test_support.h"
#include "volume/mask.h"
#include "volume/phantom.h"
#include "wdt/answer_keys.h"
#include "wdt/field_service.h"

using namespace at;
using wdt::FieldRequest;
using wdt::FieldService;

namespace {


FieldRequest requestFor(const Dataset& ds, const std::string& structure, int downsample) {
  const Structure* s = ds.findStructure(structure);
  REQUIRE(s != nullptr);
  FieldRequest r;
  r.label = s->label;
  r.params.downsample = downsample;
  r.params.backend = WdtBackend::Cpu;
  return r;
}

// Waits (at most `seconds`) until `request` is cached on the host.
std::shared_ptr<const DistanceField> waitFor(FieldService& service, const FieldRequest& request, double seconds = 60) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (std::chrono::steady_clock::now() < until) {
    if (auto c = service.cached(request); c.host) return c.host;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return nullptr;
}

}  // namespace

TEST_CASE("FieldService_FieldForAStructure_EqualsComputeWdtBitForBit") {
  const Dataset& ds = test::phantomOfSize(48);
  FieldService service(ds.volume, ds.labels, 4);
  const FieldRequest r = requestFor(ds, "cochlea", 2);
  service.request(r);
  auto field = waitFor(service, r);
  REQUIRE(field);
  auto direct = computeWdt(ds.volume, structureMask(ds.labels, r.label), r.params);
  REQUIRE(direct);
  CHECK(field->downsample == 2);
  CHECK(field->distances.voxels == direct->field.distances.voxels);
  const auto finished = service.takeFinished();
  REQUIRE(finished.size() == 1);
  CHECK(finished[0].request.key() == r.key());
  CHECK(finished[0].message.empty());
  CHECK(finished[0].device.find("CPU") != std::string::npos);
  CHECK_FALSE(service.busy());
}

TEST_CASE("FieldService_NewerRequest_CancelsTheRunningOne_AndOnlyTheNewestArrives") {
  const Dataset& ds = test::phantomOfSize(96);
  FieldService service(ds.volume, ds.labels, 4);
  // A field that only a cancel can end: a million fixed passes. (A converged 96³ field could end
  // within ~30 ms, before the newer request arrives, on a machine that stalls the test's thread.)
  FieldRequest slow = requestFor(ds, "cochlea", 1);
  slow.params.converge = false;
  slow.params.passes = 1000000;
  service.request(slow);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!service.running() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  REQUIRE(service.running());
  const FieldRequest quick = requestFor(ds, "stapes", 4);
  service.request(quick);
  REQUIRE(waitFor(service, quick));
  while (service.busy() && std::chrono::steady_clock::now() < until) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  CHECK(service.cancelledCount() == 1);
  CHECK_FALSE(service.cached(slow).ready());
  const auto finished = service.takeFinished();
  REQUIRE(finished.size() == 1);
  CHECK(finished[0].request.key() == quick.key());
}

TEST_CASE("FieldService_LruCache_KeepsTheMostRecentlyUsed") {
  const Dataset& ds = test::phantomOfSize(32);
  FieldService service(ds.volume, ds.labels, 2);
  const FieldRequest a = requestFor(ds, "cochlea", 2), b = requestFor(ds, "stapes", 2), c = requestFor(ds, "malleus", 2);
  service.request(a);
  REQUIRE(waitFor(service, a));
  service.request(b);
  REQUIRE(waitFor(service, b));
  CHECK(service.cached(a).ready());  // a is now the most recently used
  service.request(c);
  REQUIRE(waitFor(service, c));
  CHECK(service.cached(a).ready());
  CHECK_FALSE(service.cached(b).ready());
  // A cached request is not computed again.
  service.takeFinished();
  service.request(a);
  CHECK_FALSE(service.busy());
  CHECK(service.takeFinished().empty());
}

TEST_CASE("FieldService_StructureWithoutVoxels_ReportsAFailureAndCachesNothing") {
  const Dataset& ds = test::phantomOfSize(32);
  FieldService service(ds.volume, ds.labels, 2);
  FieldRequest r;
  r.label = 999;
  r.params.backend = WdtBackend::Cpu;
  service.request(r);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  std::vector<wdt::FinishedField> finished;
  while (finished.empty() && std::chrono::steady_clock::now() < until) {
    finished = service.takeFinished();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  REQUIRE(finished.size() == 1);
  CHECK_FALSE(finished[0].field);
  CHECK(finished[0].message.find("label 999") != std::string::npos);
  CHECK_FALSE(service.cached(r).ready());
}

TEST_CASE("AnswerKeyDistanceAt_EqualsTheUpsampledFieldAtTheNearestLabelVoxel") {
  const Dataset& ds = test::phantomOfSize(48);
  const Structure* cochlea = ds.findStructure("cochlea");
  REQUIRE(cochlea);
  const Mask seeds = structureMask(ds.labels, cochlea->label);
  auto keys = wdt::answerKeyDistances(ds.volume, ds.labels.geometry, seeds);
  REQUIRE(keys);
  auto coarse = computeWdt(ds.volume, seeds, wdt::answerKeyParams());
  REQUIRE(coarse);
  REQUIRE(coarse->field.downsample == 2);
  const std::uint64_t seed = test::freshSeed("AnswerKeyDistanceAt");
  std::mt19937_64 rng(seed);
  const Geometry& g = ds.labels.geometry;
  std::uniform_real_distribution<double> u(-0.2, 1.05);  // some points fall outside the grid
  int inside = 0;
  for (int n = 0; n < 400; ++n) {
    const Vec3 ijk{u(rng) * g.dims.x, u(rng) * g.dims.y, u(rng) * g.dims.z};
    const Vec3 p = g.indexToPatient(ijk);
    const auto at = wdt::answerKeyDistanceAt(coarse->field, g, p);
    const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
    if (!g.dims.contains(i, j, k)) {
      CHECK_FALSE(at);
      continue;
    }
    ++inside;
    const float expected = keys->at(i, j, k);
    if (!std::isfinite(expected)) {
      CHECK_FALSE(at);
    } else {
      REQUIRE(at);
      CHECK(*at == double(expected));
    }
  }
  CHECK(inside > 100);
}

TEST_CASE("FieldService_WaitFor_ReturnsTheFieldOnceCached_AndNeverWaitsPastItsLimitOrForNothing") {
  const Dataset& ds = test::phantomOfSize(96);
  FieldService service(ds.volume, ds.labels, 4);
  using std::chrono::milliseconds;
  using Clock = std::chrono::steady_clock;
  // Nothing asked: returns at once, empty, even with a long limit.
  const FieldRequest never = requestFor(ds, "malleus", 4);
  auto t0 = Clock::now();
  CHECK_FALSE(service.waitFor(never, milliseconds(20000)).ready());
  CHECK(Clock::now() - t0 < milliseconds(2000));
  // A long computation: the wait ends at its limit, not ready.
  FieldRequest slow = requestFor(ds, "cochlea", 1);
  slow.params.converge = true;
  service.request(slow);
  t0 = Clock::now();
  const auto early = service.waitFor(slow, milliseconds(1));
  const auto waited = Clock::now() - t0;
  if (!early.ready()) CHECK(waited < milliseconds(2000));
  // Asked and waited for long enough: the field, equal to what `cached` then holds.
  const auto done = service.waitFor(slow, milliseconds(120000));
  REQUIRE(done.ready());
  CHECK(done.host == service.cached(slow).host);
  // A cached field: returned at once.
  t0 = Clock::now();
  CHECK(service.waitFor(slow, milliseconds(20000)).ready());
  CHECK(Clock::now() - t0 < milliseconds(2000));
}

TEST_CASE("FieldService_UpdateLabels_DropsTheEditedLabelsFields_AndComputesTheNextOnTheNewLabels") {
  // Cpu, and Auto: on a machine with a CUDA device the service's device copy of the labels must be
  // made again (a stale one would give the field of the old labels).
  for (WdtBackend backend : {WdtBackend::Cpu, WdtBackend::Auto}) {
    CAPTURE(toString(backend));
    Dataset ds = test::phantomOfSize(48);  // a copy: its labels are edited below
    FieldService service(ds.volume, ds.labels, 4);
    FieldRequest edited = requestFor(ds, "cochlea", 2), kept = requestFor(ds, "stapes", 2);
    edited.params.backend = kept.params.backend = backend;
    for (const FieldRequest& r : {edited, kept}) {
      service.request(r);
      REQUIRE(waitFor(service, r));
    }
    // A slow full-resolution field is running while the labels are edited: it is cancelled and
    // waited for, so that nothing reads the labels while they change.
    FieldRequest running = requestFor(ds, "facial_nerve", 1);
    running.params.passes = 64;
    running.params.converge = false;
    running.params.backend = backend;
    service.request(running);
    const Structure* cochlea = ds.findStructure("cochlea");
    std::size_t relabelled = 0;
    service.updateLabels(
        [&] {
          for (std::uint16_t& v : ds.labels.voxels)  // the cochlea's voxels become the stapes'
            if (v == cochlea->label) {
              v = kept.label;
              ++relabelled;
            }
          // and a block of new cochlea voxels elsewhere
          for (int k = 4; k < 10; ++k)
            for (int j = 4; j < 10; ++j)
              for (int i = 4; i < 10; ++i) ds.labels.at(i, j, k) = cochlea->label;
        },
        {cochlea->label, kept.label});
    CHECK(relabelled > 0);
    CHECK_FALSE(service.cached(edited).ready());  // dropped
    CHECK_FALSE(service.cached(kept).ready());
    service.request(edited);
    auto field = waitFor(service, edited);
    REQUIRE(field);
    // The field of the edited labels: what a service made on them from the start computes.
    FieldService fresh(ds.volume, ds.labels, 1);
    fresh.request(edited);
    auto reference = waitFor(fresh, edited);
    REQUIRE(reference);
    CHECK(field->distances.voxels == reference->distances.voxels);
    if (backend == WdtBackend::Cpu) {  // and on the CPU, computeWdt's
      auto direct = computeWdt(ds.volume, structureMask(ds.labels, edited.label), edited.params);
      REQUIRE(direct);
      CHECK(field->distances.voxels == direct->field.distances.voxels);
    }
  }
}
