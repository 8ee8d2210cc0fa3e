// wdt/'s field service prefetching (a lesson's next steps computed while the student reads):
// prefetched fields equal requested ones, never hold up a request, and are never computed twice.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <thread>

#include "test_support.h"
#include "volume/mask.h"
#include "volume/phantom.h"
#include "wdt/field_service.h"

using namespace at;
using wdt::FieldRequest;
using wdt::FieldService;

namespace {

FieldRequest requestFor(const Dataset& ds, const std::string& structure, int downsample, bool converge = false) {
  const Structure* s = ds.findStructure(structure);
  REQUIRE(s != nullptr);
  FieldRequest r;
  r.label = s->label;
  r.params.downsample = downsample;
  r.params.converge = converge;
  r.params.backend = WdtBackend::Cpu;
  return r;
}

bool waitUntil(const std::function<bool()>& done, double seconds = 120) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  while (!done()) {
    if (std::chrono::steady_clock::now() > until) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

// The size of the phantom whose converged cochlea field stands for a prefetch still running when the
// test's next call comes: large enough that the field takes hundreds of milliseconds even on an
// idle machine (a converged 96³ field was done within the test's 30 ms wait), so the cases below
// meet their precondition however fast or loaded the machine is.
constexpr int kSlowFieldSize = 256;

}  // namespace

TEST_CASE("FieldService_Prefetch_ComputesTheListInOrder_WithoutCountingAsBusy") {
  const Dataset& ds = test::phantomOfSize(48);
  FieldService service(ds.volume, ds.labels, 8);
  const std::vector<FieldRequest> list{requestFor(ds, "cochlea", 1), requestFor(ds, "stapes", 1), requestFor(ds, "malleus", 2)};
  service.prefetch(list);
  CHECK(service.prefetching());
  CHECK_FALSE(service.busy());          // the view may go idle: nothing it asked for is pending
  CHECK_FALSE(service.running());       // no progress bar for a prefetch
  REQUIRE(waitUntil([&] { return !service.prefetching(); }));
  const auto finished = service.takeFinished();
  REQUIRE(finished.size() == list.size());
  for (std::size_t i = 0; i < list.size(); ++i) {
    CHECK(finished[i].request.key() == list[i].key());
    CHECK(finished[i].prefetched);
    auto cached = service.cached(list[i]);
    REQUIRE(cached.host);
    auto direct = computeWdt(ds.volume, structureMask(ds.labels, list[i].label), list[i].params);
    REQUIRE(direct);
    CHECK(cached.host->distances.voxels == direct->field.distances.voxels);
  }
  // Listing cached fields again computes nothing.
  service.prefetch(list);
  CHECK_FALSE(service.prefetching());
  service.request(list[0]);
  CHECK_FALSE(service.busy());
  CHECK(service.takeFinished().empty());
}

TEST_CASE("FieldService_RequestDuringAPrefetch_GoesFirst_AndThePrefetchIsDoneAfterwards") {
  const Dataset& ds = test::phantomOfSize(kSlowFieldSize);
  FieldService service(ds.volume, ds.labels, 8);
  const FieldRequest slow = requestFor(ds, "cochlea", 1, true);  // many passes: still running below
  service.prefetch({slow});
  REQUIRE(waitUntil([&] { return service.prefetching(); }));
  std::this_thread::sleep_for(std::chrono::milliseconds(30));  // the worker has taken it up
  const FieldRequest quick = requestFor(ds, "stapes", 4);
  service.request(quick);
  CHECK(service.busy());
  REQUIRE(waitUntil([&] { return service.cached(quick).ready(); }));
  REQUIRE(waitUntil([&] { return !service.prefetching() && !service.busy(); }));
  CHECK(service.cached(slow).ready());  // tried again once the request was served
  const auto finished = service.takeFinished();
  REQUIRE(finished.size() == 2);
  CHECK(finished[0].request.key() == quick.key());
  CHECK_FALSE(finished[0].prefetched);
  CHECK(finished[1].request.key() == slow.key());
  CHECK(finished[1].prefetched);
}

TEST_CASE("FieldService_RequestForTheFieldBeingPrefetched_TakesItOver_NotComputedTwice") {
  const Dataset& ds = test::phantomOfSize(96);
  FieldService service(ds.volume, ds.labels, 8);
  const FieldRequest slow = requestFor(ds, "cochlea", 1, true);
  service.prefetch({slow});
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  service.request(slow);  // the student reached the step before its field was ready
  REQUIRE(waitUntil([&] { return service.cached(slow).ready() && !service.busy() && !service.prefetching(); }));
  CHECK(service.cancelledCount() == 0);
  const auto finished = service.takeFinished();
  CHECK(std::count_if(finished.begin(), finished.end(), [&](const wdt::FinishedField& f) { return f.request.key() == slow.key(); }) == 1);
}

TEST_CASE("FieldService_EmptyPrefetchList_CancelsARunningPrefetch_ButNotARequest") {
  const Dataset& ds = test::phantomOfSize(kSlowFieldSize);
  FieldService service(ds.volume, ds.labels, 8);
  const FieldRequest slow = requestFor(ds, "cochlea", 1, true);
  service.prefetch({slow});
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  service.prefetch({});  // the lesson ended
  REQUIRE(waitUntil([&] { return !service.prefetching(); }));
  CHECK_FALSE(service.cached(slow).ready());
  const FieldRequest asked = requestFor(ds, "stapes", 2);
  service.request(asked);
  service.prefetch({});
  REQUIRE(waitUntil([&] { return service.cached(asked).ready(); }));
}

TEST_CASE("FieldService_ListedFields_StayCached_WhileMoreRequestsThanTheCacheHolds_PassThrough") {
  // A lesson's prefetched fields outlive a hover sweep over every structure (each hover a field):
  // the cache evicts the fields not on the list; once the list is replaced they may go too.
  const Dataset& ds = test::phantomOfSize(32);
  constexpr std::size_t kCapacity = 4;
  FieldService service(ds.volume, ds.labels, kCapacity);
  const std::vector<FieldRequest> listed{requestFor(ds, "cochlea", 1), requestFor(ds, "vestibule", 1)};
  service.prefetch(listed);
  REQUIRE(waitUntil([&] { return !service.prefetching(); }));
  int hovered = 0;
  for (const Structure& s : ds.structures) {
    if (s.id == "cochlea" || s.id == "vestibule") continue;
    FieldRequest r = requestFor(ds, s.id, 2);
    service.request(r);
    REQUIRE(waitUntil([&] { return service.cached(r).ready(); }));  // the one just put in stays
    ++hovered;
  }
  REQUIRE(hovered > int(kCapacity));  // the precondition: the requests alone overflow the cache
  for (const FieldRequest& r : listed) CHECK(service.cached(r).ready());
  service.prefetch({});
  for (const Structure& s : ds.structures) {
    if (s.id == "cochlea" || s.id == "vestibule") continue;
    FieldRequest r = requestFor(ds, s.id, 1);
    service.request(r);
    REQUIRE(waitUntil([&] { return service.cached(r).ready(); }));
  }
  CHECK_FALSE(service.cached(listed[0]).ready());  // no longer listed: evicted like any other
  CHECK_FALSE(service.cached(listed[1]).ready());
}

TEST_CASE("FieldService_HeldPrefetches_DoNotStart_RequestsStillRun_AndTheListRunsOnceReleased") {
  const Dataset& ds = test::phantomOfSize(32);
  FieldService service(ds.volume, ds.labels, 8);
  service.holdPrefetches(true);
  const FieldRequest listed = requestFor(ds, "cochlea", 1);
  service.prefetch({listed});
  const FieldRequest asked = requestFor(ds, "stapes", 1);
  service.request(asked);
  REQUIRE(waitUntil([&] { return service.cached(asked).ready(); }));  // a request is never held
  std::this_thread::sleep_for(std::chrono::milliseconds(200));           // time enough to start a 32³ field
  CHECK(service.prefetching());                                          // still listed ...
  CHECK_FALSE(service.computing(listed));                                // ... not started
  CHECK_FALSE(service.cached(listed).ready());
  service.holdPrefetches(false);
  REQUIRE(waitUntil([&] { return service.cached(listed).ready(); }));
  CHECK_FALSE(service.prefetching());
}
