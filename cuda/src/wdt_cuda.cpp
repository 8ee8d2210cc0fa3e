// Host side of the CUDA backend: device query, transfers, the pass loop (timing, convergence,
// progress, cancellation) and DeviceField.
#include "cuda/wdt_cuda.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <optional>
#include <new>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "brick_solver.h"
#include "cuda_util.h"
#include "sweep_kernels.h"
#include "wdt/huge_pages.h"

namespace at::cuda {

struct DeviceField::Impl {
  Geometry grid;
  int downsample = 1;
  DeviceBuffer<float> distances;
};

DeviceField::DeviceField() = default;
DeviceField::~DeviceField() = default;
DeviceField::DeviceField(DeviceField&&) noexcept = default;
DeviceField& DeviceField::operator=(DeviceField&&) noexcept = default;
DeviceField::DeviceField(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

const Geometry& DeviceField::grid() const {
  static const Geometry empty{};
  return impl_ ? impl_->grid : empty;
}
int DeviceField::downsample() const { return impl_ ? impl_->downsample : 1; }
const void* DeviceField::devicePointer() const { return impl_ ? impl_->distances.get() : nullptr; }

const DeviceInfo& queryDevice() {
  static const DeviceInfo info = [] {
    DeviceInfo i;
    int count = 0;
    if (const cudaError_t e = cudaGetDeviceCount(&count); e != cudaSuccess) {
      (void)cudaGetLastError();
      i.reason = std::string("cudaGetDeviceCount: ") + cudaGetErrorString(e);
      return i;
    }
    if (count == 0) {
      i.reason = "the driver reports 0 devices";
      return i;
    }
    cudaDeviceProp prop{};
    if (const cudaError_t e = cudaGetDeviceProperties(&prop, 0); e != cudaSuccess) {
      (void)cudaGetLastError();
      i.reason = std::string("cudaGetDeviceProperties: ") + cudaGetErrorString(e);
      return i;
    }
    i.name = prop.name;
    if (prop.major < 9) {
      i.reason = i.name + " has compute capability " + std::to_string(prop.major) + "." +
                 std::to_string(prop.minor) + "; this build has kernels for sm_90 (Hopper) only";
      return i;
    }
    i.available = true;
    return i;
  }();
  return info;
}

namespace {

Status validate(const WdtProblem& problem) {
  const Dims d = problem.grid.dims;
  if (d.count() == 0 || problem.density.size() != d.count() || problem.seeds.size() != d.count()) {
    return fail("WDT CUDA backend: problem arrays do not match the grid " + d.toString());
  }
  const WdtParams& p = problem.params;
  if (p.converge ? p.maxPasses < 1 : p.passes < 1) {
    return fail("WDT CUDA backend: passes must be at least 1");
  }
  if (!(p.baseCost >= 0)) return fail("WDT CUDA backend: baseCost must be >= 0");
  if (!queryDevice().available) return fail("WDT CUDA backend: " + queryDevice().reason);
  return check(cudaSetDevice(0), "cudaSetDevice(0)");
}

// Host transfers go through two page-locked staging chunks, so that the copy between the caller's
// (pageable) memory and one chunk overlaps the DMA of the other.
constexpr std::size_t kStagingBytes = std::size_t(4) << 20;

// setPersistentSweeps: Auto until set (then AT_WDT_CUDA_PERSISTENT decides: 1 on, 0 off).
std::atomic<int> gPersistentSweeps{int(PersistentSweeps::Auto)};
std::atomic<long long> gPersistentSweepsCaptured{0};

PersistentTiles persistentTiles() {
  auto mode = PersistentSweeps(gPersistentSweeps.load());
  if (mode == PersistentSweeps::Auto) {
    const char* v = std::getenv("AT_WDT_CUDA_PERSISTENT");
    if (v && std::string(v) == "1") mode = PersistentSweeps::On;
    if (v && std::string(v) == "0") mode = PersistentSweeps::Off;
  }
  switch (mode) {
    case PersistentSweeps::On: return PersistentTiles::All;
    case PersistentSweeps::Off: return PersistentTiles::None;
    case PersistentSweeps::Auto: break;
  }
  return PersistentTiles::Large;
}

// What one captured pass depends on besides the workspace's buffers.
struct PassKey {
  float spacing[3] = {0, 0, 0};
  float baseCost = 0;
  StepRule rule = StepRule::Entering;
  WeightRule weight = WeightRule::Density;
  PersistentTiles persistent = PersistentTiles::None;  // persistent sweeps (setPersistentSweeps)
  bool operator==(const PassKey& o) const {
    return spacing[0] == o.spacing[0] && spacing[1] == o.spacing[1] && spacing[2] == o.spacing[2] &&
           baseCost == o.baseCost && rule == o.rule && weight == o.weight && persistent == o.persistent;
  }
};

// Everything a run on one grid size needs: device buffers, staging, stream, events and the
// captured pass. Kept between calls (see WorkspaceCache): allocation, graph capture and
// instantiation then cost nothing on the next call of the same size.
struct Workspace {
  Dims dims;
  Stream stream;
  DeviceBuffer<std::uint8_t> density, densityT;  // densityT: y-contiguous copy for the x sweeps
  DeviceBuffer<float> a, b;  // the field (in `a` between passes) and the sweeps' second buffer
  DeviceBuffer<int> flag;  // whether a problem built on the GPU has any seed (launchBuildProblem)
  PinnedBuffer<int> flagHost;
  DeviceBuffer<unsigned long long> lowered;  // voxels a pass lowered (sweep kernels add to it)
  PinnedBuffer<unsigned long long> loweredHost;
  DeviceBuffer<unsigned> progress;  // the persistent sweeps' tile counters, kSweepProgressCounters a sweep
  PinnedBuffer<std::uint8_t> staging[2];
  Event chunkDone[2];
  Event start, end;
  GraphExec pass;
  std::optional<PassKey> passKey;
  // Converge mode's brick solver (brick_solver.h), allocated on its first use: a second halo
  // snapshot (`b` is the first), brick flags and lists, 3 counters then 2 result ints.
  DeviceBuffer<float> shell1;
  DeviceBuffer<int> brickFlags, brickLists, brickCounters;
  PinnedBuffer<int> brickResultHost;

  Status allocateBrickSolver() {
    if (shell1.get()) return {};
    const std::size_t bricks = brickCount(dims.x, dims.y, dims.z);
    DeviceBuffer<float> s;
    DeviceBuffer<int> f, l, c;
    PinnedBuffer<int> r;
    AT_ASSIGN(s, DeviceBuffer<float>::allocate(dims.count()));
    AT_ASSIGN(f, DeviceBuffer<int>::allocate(2 * bricks));
    AT_ASSIGN(l, DeviceBuffer<int>::allocate(2 * bricks));
    AT_ASSIGN(c, DeviceBuffer<int>::allocate(5));
    AT_ASSIGN(r, PinnedBuffer<int>::allocate(2));
    shell1 = std::move(s), brickFlags = std::move(f), brickLists = std::move(l), brickCounters = std::move(c);
    brickResultHost = std::move(r);
    return {};
  }

  static Result<std::unique_ptr<Workspace>> create(Dims dims) {
    const std::size_t n = dims.count();
    auto w = std::make_unique<Workspace>();
    w->dims = dims;
    AT_ASSIGN(w->stream, Stream::create());
    AT_ASSIGN(w->density, DeviceBuffer<std::uint8_t>::allocate(n));
    AT_ASSIGN(w->densityT, DeviceBuffer<std::uint8_t>::allocate(n));
    AT_ASSIGN(w->a, DeviceBuffer<float>::allocate(n));
    AT_ASSIGN(w->b, DeviceBuffer<float>::allocate(n));
    AT_ASSIGN(w->flag, DeviceBuffer<int>::allocate(1));
    AT_ASSIGN(w->flagHost, PinnedBuffer<int>::allocate(1));
    AT_ASSIGN(w->lowered, DeviceBuffer<unsigned long long>::allocate(1));
    AT_ASSIGN(w->loweredHost, PinnedBuffer<unsigned long long>::allocate(1));
    AT_ASSIGN(w->progress, DeviceBuffer<unsigned>::allocate(6 * std::size_t(kSweepProgressCounters)));
    for (int i = 0; i < 2; ++i) {
      AT_ASSIGN(w->staging[i], PinnedBuffer<std::uint8_t>::allocate(kStagingBytes));
      AT_ASSIGN(w->chunkDone[i], Event::create(cudaEventDisableTiming));
    }
    AT_ASSIGN(w->start, Event::create());
    AT_ASSIGN(w->end, Event::create());
    return w;
  }

  // Copies `bytes` from host `from` to device `to` (upload) or back (download), staged.
  Status transfer(void* to, const void* from, std::size_t bytes, bool upload) {
    const cudaStream_t s = stream.get();
    const char* what = upload ? "cudaMemcpyAsync(host to device)" : "cudaMemcpyAsync(device to host)";
    std::size_t chunks = (bytes + kStagingBytes - 1) / kStagingBytes;
    auto part = [&](std::size_t i) { return std::min(kStagingBytes, bytes - i * kStagingBytes); };
    if (upload) {
      for (std::size_t i = 0; i < chunks; ++i) {
        const int k = int(i % 2);
        // The chunk's previous DMA — of this transfer or of an earlier one still in flight —
        // must have read it before the host overwrites it (waiting on a never-recorded event
        // returns at once).
        AT_TRY(chunkDone[k].synchronize());
        std::memcpy(staging[k].get(), static_cast<const std::uint8_t*>(from) + i * kStagingBytes, part(i));
        AT_TRY(check(cudaMemcpyAsync(static_cast<std::uint8_t*>(to) + i * kStagingBytes, staging[k].get(), part(i),
                                     cudaMemcpyHostToDevice, s),
                     what));
        AT_TRY(chunkDone[k].record(stream));
      }
      return {};
    }
    auto enqueue = [&](std::size_t i) -> Status {
      const int k = int(i % 2);
      AT_TRY(check(cudaMemcpyAsync(staging[k].get(), static_cast<const std::uint8_t*>(from) + i * kStagingBytes,
                                   part(i), cudaMemcpyDeviceToHost, s),
                   what));
      return chunkDone[k].record(stream);
    };
    if (chunks > 0) AT_TRY(enqueue(0));
    for (std::size_t i = 0; i < chunks; ++i) {
      if (i + 1 < chunks) AT_TRY(enqueue(i + 1));  // in flight while chunk i is copied out
      AT_TRY(chunkDone[i % 2].synchronize());
      std::memcpy(static_cast<std::uint8_t*>(to) + i * kStagingBytes, staging[i % 2].get(), part(i));
    }
    return {};
  }
};

// The workspaces of the most recent grid sizes (a hover field and a full field alternate in the
// app). A call takes one out (or makes one) and puts it back when done, so concurrent calls never
// share one.
class WorkspaceCache {
 public:
  static WorkspaceCache& instance() {
    // Never destroyed: freeing CUDA resources from a static destructor races the runtime's own
    // teardown at exit; the process's exit releases them.
    static WorkspaceCache* cache = new WorkspaceCache;
    return *cache;
  }
  // A kept workspace of these dims, or null.
  std::unique_ptr<Workspace> takeKept(Dims dims) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = kept_.begin(); it != kept_.end(); ++it) {
      if ((*it)->dims == dims) {
        auto w = std::move(*it);
        kept_.erase(it);
        return w;
      }
    }
    return nullptr;
  }
  // A kept workspace of these dims, or a new one; if allocating fails, the kept workspaces are
  // freed and the allocation is tried once more.
  Result<std::unique_ptr<Workspace>> take(Dims dims) {
    if (auto kept = takeKept(dims)) return kept;
    auto made = Workspace::create(dims);
    if (made) return made;
    std::vector<std::unique_ptr<Workspace>> freed;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      freed.swap(kept_);
    }
    if (freed.empty()) return made;
    freed.clear();
    return Workspace::create(dims);
  }
  void put(std::unique_ptr<Workspace> w) {
    std::lock_guard<std::mutex> lock(mutex_);
    kept_.insert(kept_.begin(), std::move(w));
    if (kept_.size() > kKept) kept_.pop_back();
  }

 private:
  static constexpr std::size_t kKept = 2;
  std::mutex mutex_;
  std::vector<std::unique_ptr<Workspace>> kept_;
};

// Captures one pass as a CUDA graph, reused while the key matches: the x sweeps run on a copy of
// the field transposed to y-contiguous layout (so that every sweep's lanes are coalesced), then
// the y and z sweeps; the field starts and ends the pass in `a`.
Status preparePass(Workspace& w, const Geometry& grid, const WdtParams& params) {
  const Dims d = w.dims;
  PassKey key;
  for (int i = 0; i < 3; ++i) key.spacing[i] = float(grid.spacingMm[i]);
  key.baseCost = params.baseCost;
  key.rule = params.rule;
  key.weight = params.weight;
  key.persistent = persistentTiles();
  if (w.passKey && *w.passKey == key) return {};
  w.passKey.reset();

  int persistentLaunches = 0;  // sweeps of the pass captured as persistent launches
  auto enqueuePass = [&](cudaStream_t st) -> Status {
    ExactSweepArgs e;
    e.baseCost = key.baseCost;
    e.rule = key.rule;
    e.weight = key.weight;
    e.lowered = w.lowered.get();
    e.persistentLaunches = &persistentLaunches;
    // Persistent sweeps: each sweep its own tile progress counters, all zeroed once a pass, before
    // the pass's first persistent launch (none on a pass without one).
    e.persistent = key.persistent;
    bool zeroed = false;
    e.zeroProgress = [&]() -> Status {
      if (zeroed) return {};
      zeroed = true;
      return check(cudaMemsetAsync(w.progress.get(), 0, w.progress.size() * sizeof(unsigned), st),
                   "cudaMemsetAsync(sweep progress counters)");
    };
    int sweep = 0;
    auto counters = [&]() -> unsigned* {
      return key.persistent != PersistentTiles::None ? w.progress.get() + std::size_t(sweep++) * kSweepProgressCounters
                                                     : nullptr;
    };
    const float sx = key.spacing[0], sy = key.spacing[1], sz = key.spacing[2];
    const std::size_t nxy = std::size_t(d.x) * d.y;
    float* a = w.a.get();
    float* b = w.b.get();
    // x sweeps on the transposed field (y contiguous): lanes y, z; planes x.
    AT_TRY(launchTransposeXY(a, b, d.x, d.y, d.z, st));
    e.density = w.densityT.get();
    e.nu = d.y, e.nv = d.z, e.na = d.x, e.strideV = nxy, e.strideA = std::size_t(d.y);
    e.lengths = wdt::axisSweepLengths(0, sx, sy, sz);
    e.src = b, e.dst = a, e.direction = +1;
    e.progress = counters();
    AT_TRY(launchExactSweep(e, st));
    e.src = a, e.dst = b, e.direction = -1;
    e.progress = counters();
    AT_TRY(launchExactSweep(e, st));
    AT_TRY(launchTransposeXY(b, a, d.y, d.x, d.z, st));
    // y sweeps: lanes x, z; planes y.  z sweeps: lanes x, y; planes z.
    e.density = w.density.get();
    e.nu = d.x, e.nv = d.z, e.na = d.y, e.strideV = nxy, e.strideA = std::size_t(d.x);
    e.lengths = wdt::axisSweepLengths(1, sx, sy, sz);
    e.src = a, e.dst = b, e.direction = +1;
    e.progress = counters();
    AT_TRY(launchExactSweep(e, st));
    e.src = b, e.dst = a, e.direction = -1;
    e.progress = counters();
    AT_TRY(launchExactSweep(e, st));
    e.nu = d.x, e.nv = d.y, e.na = d.z, e.strideV = std::size_t(d.x), e.strideA = nxy;
    e.lengths = wdt::axisSweepLengths(2, sx, sy, sz);
    e.src = a, e.dst = b, e.direction = +1;
    e.progress = counters();
    AT_TRY(launchExactSweep(e, st));
    e.src = b, e.dst = a, e.direction = -1;
    e.progress = counters();
    return launchExactSweep(e, st);
  };
  AT_ASSIGN(w.pass, GraphExec::capture(w.stream, enqueuePass));
  gPersistentSweepsCaptured += persistentLaunches;
  w.passKey = key;
  return {};
}

// Seeds live, as bytes, in the second distance buffer's memory until launchInitDistances.
std::uint8_t* seedBytes(Workspace& w) { return reinterpret_cast<std::uint8_t*>(w.b.get()); }

// With the density in w.density and the seeds in seedBytes(w): the initial field in w.a, the
// transposed density, and the captured pass.
Status finishLoading(Workspace& w, const Geometry& grid, const WdtParams& params) {
  const cudaStream_t s = w.stream.get();
  AT_TRY(launchInitDistances(w.a.get(), seedBytes(w), w.dims.count(), s));
  AT_TRY(launchTransposeXY(w.density.get(), w.densityT.get(), w.dims.x, w.dims.y, w.dims.z, s));
  return preparePass(w, grid, params);
}

// Uploads a host problem.
Status loadHostProblem(Workspace& w, const WdtProblem& problem) {
  const std::size_t n = w.dims.count();
  AT_TRY(w.transfer(seedBytes(w), problem.seeds.data(), n, true));
  AT_TRY(w.transfer(w.density.get(), problem.density.data(), n, true));
  return finishLoading(w, problem.grid, problem.params);
}

// Whole-volume passes before the brick rounds in converge mode; negative: the default below.
std::atomic<int> gSweepsBeforeBricks{-1};

// The default, measured on an H100 (bench/RESULTS.md, sixth and seventh sessions). Up to 128³
// voxels, rounds from the seeds were fastest on every input (synthetic head, cochlea phantom, both
// real-CT structures). Above, passes first: 2, and a third when the second lowered more than
// kThirdPassLowered values per voxel (a sweep that still lowers many values means paths that
// still wind: the rounds would need many more visits than one more pass costs). On seven phantom
// structures and the synthetic head at 256³ and 512³, the second pass lowered 0.36–0.98 values
// per voxel where 2 passes were fastest and 1.36–1.82 where 3 were (the cochlea, the sigmoid
// sinus); a fourth pass was slower everywhere.
constexpr double kThirdPassLowered = 1.15;

// Whether converge mode runs another whole-volume pass before the brick rounds, after `done`
// passes of which the last lowered `lastLowered` values.
bool anotherPassBeforeBricks(Dims d, int done, unsigned long long lastLowered) {
  const int forced = gSweepsBeforeBricks.load();
  if (forced >= 0) return done < forced;
  if (d.count() <= std::size_t(128) * 128 * 128) return false;
  if (done < 2) return true;
  return done == 2 && double(lastLowered) > kThirdPassLowered * double(d.count());
}

// Brick rounds (brick_solver.h) from the field in w.a, at most maxPasses × 2 × (bricks along the
// longest axis) rounds. Cancellation is looked at before the rounds start (they take
// milliseconds).
Status runBrickRounds(Workspace& w, const WdtParams& params, const WdtControl& control, WdtStats& stats) {
  const cudaStream_t s = w.stream.get();
  const Dims d = w.dims;
  if (control.cancel && control.cancel->load(std::memory_order_relaxed)) {
    stats.cancelled = true;
    return {};
  }
  stats.scheme = stats.passesRun > 0 ? "sweeps+bricks" : "bricks";
  BrickSolveBuffers b;
  b.field = w.a.get();
  b.density = w.density.get();
  b.shell[0] = w.b.get();
  b.shell[1] = w.shell1.get();
  b.flags = w.brickFlags.get();
  b.lists = w.brickLists.get();
  b.counters = w.brickCounters.get();
  b.result = w.brickCounters.get() + 3;
  BrickSolveParams bp;
  for (int i = 0; i < 3; ++i) bp.spacing[i] = w.passKey->spacing[i];
  bp.baseCost = params.baseCost;
  bp.rule = params.rule;
  bp.weight = params.weight;
  const long longest = (std::max({d.x, d.y, d.z}) + kBrickEdge - 1) / kBrickEdge;
  bp.maxRounds = int(std::min<long>(long(params.maxPasses) * 2 * longest, 1L << 30));
  AT_TRY(w.start.record(w.stream));
  AT_TRY(launchBrickSolve(b, d.x, d.y, d.z, bp, s));
  AT_TRY(w.end.record(w.stream));
  AT_TRY(check(cudaMemcpyAsync(w.brickResultHost.get(), b.result, 2 * sizeof(int), cudaMemcpyDeviceToHost, s),
               "cudaMemcpyAsync(brick solver result, device to host)"));
  AT_TRY(w.stream.synchronize());
  auto ms = w.end.millisecondsSince(w.start);
  if (!ms) return tl::unexpected(ms.error());
  stats.msCompute += *ms;
  stats.rounds = w.brickResultHost.get()[0];
  stats.converged = w.brickResultHost.get()[1] == 0;
  return {};
}

// Runs the passes on a loaded workspace; the field ends in w.a. Converge mode, where the brick
// solver's buffers can be allocated, runs the passes anotherPassBeforeBricks asks for and then
// brick rounds.
Status runPasses(Workspace& w, const WdtParams& params, const WdtControl& control, WdtStats& stats) {
  const cudaStream_t s = w.stream.get();

  stats.backendUsed = WdtBackend::Cuda;
  stats.device = queryDevice().name;
  const bool bricks = params.converge && w.allocateBrickSolver();
  const int limit = !params.converge ? params.passes : params.maxPasses;
  bool lastChanged = true;
  unsigned long long lastLowered = 0;
  bool another = !bricks || anotherPassBeforeBricks(w.dims, 0, 0);  // whether pass `pass` runs
  for (int pass = 0; pass < limit && another; ++pass) {
    if (control.cancel && control.cancel->load(std::memory_order_relaxed)) {
      stats.cancelled = true;
      break;
    }
    AT_TRY(check(cudaMemsetAsync(w.lowered.get(), 0, sizeof(unsigned long long), s), "cudaMemsetAsync(lowered count)"));
    AT_TRY(w.start.record(w.stream));
    AT_TRY(w.pass.launch(w.stream));
    AT_TRY(w.end.record(w.stream));
    AT_TRY(check(cudaMemcpyAsync(w.loweredHost.get(), w.lowered.get(), sizeof(unsigned long long),
                                 cudaMemcpyDeviceToHost, s),
                 "cudaMemcpyAsync(lowered count, device to host)"));
    AT_TRY(w.stream.synchronize());
    auto ms = w.end.millisecondsSince(w.start);
    if (!ms) return tl::unexpected(ms.error());
    stats.msPerPass.push_back(*ms);
    stats.msCompute += *ms;
    stats.passesRun = pass + 1;
    lastLowered = *w.loweredHost.get();
    lastChanged = lastLowered != 0;
    another = !bricks || anotherPassBeforeBricks(w.dims, pass + 1, lastLowered);
    // Passes planned, as far as known: with brick rounds, this one and the next if it will run.
    const int planned = !bricks ? limit : std::min(limit, another ? pass + 2 : pass + 1);
    if (control.progress) control.progress(pass + 1, planned);
    if (params.converge && !lastChanged) break;
  }
  AT_TRY(w.stream.synchronize());
  stats.converged = stats.passesRun > 0 && !lastChanged && !stats.cancelled;
  if (bricks && !stats.converged && !stats.cancelled) AT_TRY(runBrickRounds(w, params, control, stats));
  return {};
}

}  // namespace

double deviceMemoryUsedMiB() {
  if (!queryDevice().available) return -1;
  std::size_t freeBytes = 0, totalBytes = 0;
  if (cudaMemGetInfo(&freeBytes, &totalBytes) != cudaSuccess) {
    (void)cudaGetLastError();
    return -1;
  }
  return double(totalBytes - freeBytes) / (1024.0 * 1024.0);
}

void setConvergeSweepsBeforeBricks(int passes) { gSweepsBeforeBricks = passes < 0 ? -1 : passes; }
void setPersistentSweeps(PersistentSweeps mode) { gPersistentSweeps = int(mode); }
long long persistentSweepsCaptured() { return gPersistentSweepsCaptured.load(); }

Result<DeviceField> makeDeviceField(const Geometry& grid, float fill) {
  if (!queryDevice().available) return fail("CUDA device field: " + queryDevice().reason);
  AT_TRY(check(cudaSetDevice(0), "cudaSetDevice(0)"));
  auto impl = std::make_unique<DeviceField::Impl>();
  impl->grid = grid;
  auto buffer = DeviceBuffer<float>::allocate(grid.dims.count());
  if (!buffer) return tl::unexpected(withContext("device field " + grid.dims.toString(), buffer.error()));
  impl->distances = std::move(*buffer);
  AT_TRY(launchFill(impl->distances.get(), impl->distances.size(), fill, nullptr));
  AT_TRY(check(cudaDeviceSynchronize(), "cudaDeviceSynchronize"));
  return DeviceField(std::move(impl));
}

// The field leaves in its own buffer; the workspace keeps its buffers for the next call.
Result<std::unique_ptr<DeviceField::Impl>> takeField(std::unique_ptr<Workspace> w, const Geometry& grid, int downsample,
                                                     std::chrono::steady_clock::time_point t0, WdtStats& stats,
                                                     WdtStats* statsOut) {
  auto impl = std::make_unique<DeviceField::Impl>();
  impl->grid = grid;
  impl->downsample = downsample;
  AT_ASSIGN(impl->distances, DeviceBuffer<float>::allocate(w->a.size()));
  AT_TRY(check(cudaMemcpyAsync(impl->distances.get(), w->a.get(), w->a.bytes(), cudaMemcpyDeviceToDevice, w->stream.get()),
               "cudaMemcpyAsync(distances, device to device)"));
  AT_TRY(w->stream.synchronize());
  WorkspaceCache::instance().put(std::move(w));
  stats.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (statsOut) *statsOut = std::move(stats);
  return impl;
}

Result<DeviceField> runCudaBackendOnDevice(const WdtProblem& problem, const WdtControl& control, WdtStats* statsOut) {
  const auto t0 = std::chrono::steady_clock::now();
  AT_TRY(validate(problem));
  std::unique_ptr<Workspace> w;
  AT_ASSIGN(w, WorkspaceCache::instance().take(problem.grid.dims));
  WdtStats stats;
  AT_TRY(loadHostProblem(*w, problem));
  AT_TRY(runPasses(*w, problem.params, control, stats));
  auto impl = takeField(std::move(w), problem.grid, problem.params.downsample, t0, stats, statsOut);
  if (!impl) return tl::unexpected(impl.error());
  return DeviceField(std::move(*impl));
}

Status copyToHost(const DeviceField& field, FloatVolume& out) {
  out.geometry = field.grid();
  out.voxels.resize(field.grid().dims.count());
  if (out.voxels.empty()) return {};
  const std::size_t bytes = out.voxels.size() * sizeof(float);
  // Through the pinned staging chunks of the workspace kept from the run that made the field, when
  // there is one: a plain copy into pageable memory runs at a fraction of the speed.
  if (auto w = WorkspaceCache::instance().takeKept(field.grid().dims)) {
    AT_TRY(w->transfer(out.voxels.data(), field.devicePointer(), bytes, false));
    WorkspaceCache::instance().put(std::move(w));
    return {};
  }
  return check(cudaMemcpy(out.voxels.data(), field.devicePointer(), bytes, cudaMemcpyDeviceToHost),
               "cudaMemcpy(distances, device to host)");
}

Result<WdtResult> runCudaBackend(const WdtProblem& problem, const WdtControl& control) {
  const auto t0 = std::chrono::steady_clock::now();
  AT_TRY(validate(problem));
  std::unique_ptr<Workspace> w;
  AT_ASSIGN(w, WorkspaceCache::instance().take(problem.grid.dims));
  WdtResult result;
  FloatVolume& out = result.field.distances;
  out.geometry = problem.grid;
  {
    // The host field is allocated on a second thread while the GPU runs.
    bool allocated = true;
    std::jthread allocation([&] {
      try {
        wdt::resizeOnHugePages(out.voxels, w->a.size());
      } catch (const std::bad_alloc&) {
        allocated = false;
      }
    });
    AT_TRY(loadHostProblem(*w, problem));
    AT_TRY(runPasses(*w, problem.params, control, result.stats));
    allocation.join();
    if (!allocated) {
      return fail("WDT CUDA backend: cannot allocate " + std::to_string(w->a.bytes()) + " bytes of host memory for the field");
    }
  }
  AT_TRY(w->transfer(out.voxels.data(), w->a.get(), w->a.bytes(), false));
  WorkspaceCache::instance().put(std::move(w));
  result.field.downsample = problem.params.downsample;
  result.stats.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

struct DeviceVolume::Impl {
  Geometry grid;
  DeviceBuffer<std::int16_t> hu;
  DeviceBuffer<std::uint16_t> labels;
  DeviceBuffer<std::uint8_t> lut;                   // densityTable of `window`
  std::optional<std::pair<float, float>> window;    // HU window the table holds
  std::mutex mutex;                                 // one call at a time (the table is shared)
};

DeviceVolume::DeviceVolume() = default;
DeviceVolume::~DeviceVolume() = default;
DeviceVolume::DeviceVolume(DeviceVolume&&) noexcept = default;
DeviceVolume& DeviceVolume::operator=(DeviceVolume&&) noexcept = default;
DeviceVolume::DeviceVolume(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

const Geometry& DeviceVolume::grid() const {
  static const Geometry empty{};
  return impl_ ? impl_->grid : empty;
}

Result<DeviceVolume> uploadVolume(const Volume& volume, const LabelMap& labels) {
  const Dims d = volume.dims();
  if (d.count() == 0 || volume.voxels.size() != d.count()) return fail("CUDA device volume: the volume is empty (" + d.toString() + ")");
  if (!(labels.dims() == d) || labels.voxels.size() != d.count())
    return fail("CUDA device volume: the label map is " + labels.dims().toString() + " but the volume is " + d.toString());
  if (!queryDevice().available) return fail("CUDA device volume: " + queryDevice().reason);
  AT_TRY(check(cudaSetDevice(0), "cudaSetDevice(0)"));
  auto impl = std::make_unique<DeviceVolume::Impl>();
  impl->grid = volume.geometry;
  AT_ASSIGN(impl->hu, DeviceBuffer<std::int16_t>::allocate(d.count()));
  AT_ASSIGN(impl->labels, DeviceBuffer<std::uint16_t>::allocate(d.count()));
  AT_ASSIGN(impl->lut, DeviceBuffer<std::uint8_t>::allocate(65536));
  AT_TRY(check(cudaMemcpy(impl->hu.get(), volume.voxels.data(), impl->hu.bytes(), cudaMemcpyHostToDevice),
               "cudaMemcpy(HU volume, host to device)"));
  AT_TRY(check(cudaMemcpy(impl->labels.get(), labels.voxels.data(), impl->labels.bytes(), cudaMemcpyHostToDevice),
               "cudaMemcpy(label map, host to device)"));
  return DeviceVolume(std::move(impl));
}

Result<DeviceField> runCudaBackendOnDevice(const DeviceVolume& volume, std::uint16_t label, const WdtParams& params,
                                           const WdtControl& control, WdtStats* statsOut) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!volume.impl_) return fail("WDT CUDA backend: the device volume is empty");
  AT_TRY(validateWdtParams(params));
  if (!queryDevice().available) return fail("WDT CUDA backend: " + queryDevice().reason);
  AT_TRY(check(cudaSetDevice(0), "cudaSetDevice(0)"));
  DeviceVolume::Impl& v = *volume.impl_;
  std::lock_guard lock(v.mutex);
  if (!v.window || v.window->first != params.huMin || v.window->second != params.huMax) {
    const std::vector<std::uint8_t> lut = densityTable(params);
    v.window.reset();
    AT_TRY(check(cudaMemcpy(v.lut.get(), lut.data(), lut.size(), cudaMemcpyHostToDevice),
                 "cudaMemcpy(density table, host to device)"));
    v.window = std::make_pair(params.huMin, params.huMax);
  }
  const int f = params.downsample;
  const Geometry grid = f == 1 ? v.grid : downsampledGrid(v.grid, f);
  std::unique_ptr<Workspace> w;
  AT_ASSIGN(w, WorkspaceCache::instance().take(grid.dims));
  const cudaStream_t s = w->stream.get();
  BuildProblemArgs build;
  build.hu = v.hu.get();
  build.labels = v.labels.get();
  build.lut = v.lut.get();
  build.label = label;
  build.factor = f;
  build.fine = {v.grid.dims.x, v.grid.dims.y, v.grid.dims.z};
  build.coarse = {grid.dims.x, grid.dims.y, grid.dims.z};
  build.density = w->density.get();
  build.seeds = seedBytes(*w);
  build.anySeed = w->flag.get();
  AT_TRY(check(cudaMemsetAsync(w->flag.get(), 0, sizeof(int), s), "cudaMemsetAsync(seed flag)"));
  AT_TRY(launchBuildProblem(build, s));
  AT_TRY(check(cudaMemcpyAsync(w->flagHost.get(), w->flag.get(), sizeof(int), cudaMemcpyDeviceToHost, s),
               "cudaMemcpyAsync(seed flag, device to host)"));
  AT_TRY(finishLoading(*w, grid, params));
  AT_TRY(w->stream.synchronize());
  if (*w->flagHost.get() == 0) {
    WorkspaceCache::instance().put(std::move(w));
    return fail("WDT: no voxel carries label " + std::to_string(label) + " (the structure mask is empty)");
  }
  WdtStats stats;
  AT_TRY(runPasses(*w, params, control, stats));
  auto impl = takeField(std::move(w), grid, f, t0, stats, statsOut);
  if (!impl) return tl::unexpected(impl.error());
  return DeviceField(std::move(*impl));
}

}  // namespace at::cuda
