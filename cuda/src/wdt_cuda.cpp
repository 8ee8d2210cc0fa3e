// Host side of the CUDA backend: device query, transfers, the pass loop (timing, convergence,
// progress, cancellation) and DeviceField.
#include "cuda/wdt_cuda.h"

#include <cuda_runtime.h>

#include <chrono>
#include <cstdlib>
#include <cstdint>
#include <utility>

#include "cuda_util.h"
#include "sweep_kernels.h"

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

enum class Scheme { Exact, Tiled };

// The exact scheme (exact_sweep.cu) unless AT_WDT_CUDA_SCHEME=tiled selects the single-launch
// tiled scheme (sweep_kernels.cu), kept for comparison: faster per pass, but each pass propagates
// less across tile borders, so fixed-pass fields are less accurate and converging takes more passes.
Scheme sweepScheme() {
  const char* env = std::getenv("AT_WDT_CUDA_SCHEME");
  return env && std::string(env) == "tiled" ? Scheme::Tiled : Scheme::Exact;
}

#define AT_TRY(expr)                                          \
  do {                                                        \
    if (auto at_status_ = (expr); !at_status_)                \
      return tl::unexpected(std::move(at_status_).error());   \
  } while (0)

}  // namespace

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

Result<DeviceField> runCudaBackendOnDevice(const WdtProblem& problem, const WdtControl& control, WdtStats* statsOut) {
  const auto t0 = std::chrono::steady_clock::now();
  AT_TRY(validate(problem));
  const Dims dims = problem.grid.dims;
  const std::size_t n = dims.count();
  const WdtParams& params = problem.params;

  auto stream = Stream::create();
  if (!stream) return tl::unexpected(stream.error());
  auto density = DeviceBuffer<std::uint8_t>::allocate(n);
  if (!density) return tl::unexpected(density.error());
  auto a = DeviceBuffer<float>::allocate(n);
  if (!a) return tl::unexpected(a.error());
  auto b = DeviceBuffer<float>::allocate(n);
  if (!b) return tl::unexpected(b.error());
  auto flag = DeviceBuffer<int>::allocate(1);
  if (!flag) return tl::unexpected(flag.error());
  auto flagHost = PinnedBuffer<int>::allocate(1);
  if (!flagHost) return tl::unexpected(flagHost.error());
  auto start = Event::create();
  if (!start) return tl::unexpected(start.error());
  auto end = Event::create();
  if (!end) return tl::unexpected(end.error());
  const cudaStream_t s = stream->get();

  {
    // Seeds travel once, through the second distance buffer's memory viewed as bytes.
    std::uint8_t* seeds = reinterpret_cast<std::uint8_t*>(b->get());
    AT_TRY(check(cudaMemcpyAsync(density->get(), problem.density.data(), n, cudaMemcpyHostToDevice, s),
                 "cudaMemcpyAsync(density, host to device)"));
    AT_TRY(check(cudaMemcpyAsync(seeds, problem.seeds.data(), n, cudaMemcpyHostToDevice, s),
                 "cudaMemcpyAsync(seeds, host to device)"));
    AT_TRY(launchInitDistances(a->get(), seeds, n, s));
  }

  // One pass, as a fixed sequence of launches that starts and ends with the field in `a`.
  const Scheme scheme = sweepScheme();
  DeviceBuffer<std::uint8_t> densityT;  // y-contiguous copy for the exact scheme's x sweeps
  if (scheme == Scheme::Exact) {
    AT_TRY(prepareExactSweeps());
    auto t = DeviceBuffer<std::uint8_t>::allocate(n);
    if (!t) return tl::unexpected(t.error());
    densityT = std::move(*t);
    AT_TRY(launchTransposeXY(density->get(), densityT.get(), dims.x, dims.y, dims.z, s));
  }
  const float sx = float(problem.grid.spacingMm[0]), sy = float(problem.grid.spacingMm[1]),
              sz = float(problem.grid.spacingMm[2]);
  auto enqueuePass = [&](cudaStream_t st) -> Status {
    if (scheme == Scheme::Tiled) {
      SweepArgs args;
      args.density = density->get();
      args.nx = dims.x, args.ny = dims.y, args.nz = dims.z;
      args.spacing[0] = sx, args.spacing[1] = sy, args.spacing[2] = sz;
      args.baseCost = params.baseCost;
      args.rule = params.rule;
      args.weight = params.weight;
      args.changed = flag->get();
      float* cur = a->get();
      float* next = b->get();
      for (int axis = 0; axis < 3; ++axis) {
        for (int direction : {+1, -1}) {
          args.src = cur;
          args.dst = next;
          AT_TRY(launchSweep(args, axis, direction, st));
          std::swap(cur, next);
        }
      }
      return {};  // six swaps: the field is back in `a`
    }
    ExactSweepArgs e;
    e.baseCost = params.baseCost;
    e.rule = params.rule;
    e.weight = params.weight;
    e.changed = flag->get();
    const std::size_t nxy = std::size_t(dims.x) * dims.y;
    // x sweeps on the transposed field (y contiguous): lanes y, z; planes x.
    AT_TRY(launchTransposeXY(a->get(), b->get(), dims.x, dims.y, dims.z, st));
    e.density = densityT.get();
    e.nu = dims.y, e.nv = dims.z, e.na = dims.x, e.strideV = nxy, e.strideA = std::size_t(dims.y);
    e.lengths = wdt::axisSweepLengths(0, sx, sy, sz);
    e.src = b->get(), e.dst = a->get(), e.direction = +1;
    AT_TRY(launchExactSweep(e, st));
    e.src = a->get(), e.dst = b->get(), e.direction = -1;
    AT_TRY(launchExactSweep(e, st));
    AT_TRY(launchTransposeXY(b->get(), a->get(), dims.y, dims.x, dims.z, st));
    // y sweeps: lanes x, z; planes y.  z sweeps: lanes x, y; planes z.
    e.density = density->get();
    e.nu = dims.x, e.nv = dims.z, e.na = dims.y, e.strideV = nxy, e.strideA = std::size_t(dims.x);
    e.lengths = wdt::axisSweepLengths(1, sx, sy, sz);
    e.src = a->get(), e.dst = b->get(), e.direction = +1;
    AT_TRY(launchExactSweep(e, st));
    e.src = b->get(), e.dst = a->get(), e.direction = -1;
    AT_TRY(launchExactSweep(e, st));
    e.nu = dims.x, e.nv = dims.y, e.na = dims.z, e.strideV = std::size_t(dims.x), e.strideA = nxy;
    e.lengths = wdt::axisSweepLengths(2, sx, sy, sz);
    e.src = a->get(), e.dst = b->get(), e.direction = +1;
    AT_TRY(launchExactSweep(e, st));
    e.src = b->get(), e.dst = a->get(), e.direction = -1;
    return launchExactSweep(e, st);
  };
  // The pass is captured once into a CUDA graph and replayed: tens of launches per pass then cost
  // one launch call. Cancellation is therefore checked between passes.
  auto graph = GraphExec::capture(*stream, enqueuePass);
  if (!graph) return tl::unexpected(graph.error());

  WdtStats stats;
  stats.backendUsed = WdtBackend::Cuda;
  stats.device = queryDevice().name;
  const int planned = params.converge ? params.maxPasses : params.passes;
  bool lastChanged = true;
  for (int pass = 0; pass < planned; ++pass) {
    if (control.cancel && control.cancel->load(std::memory_order_relaxed)) {
      stats.cancelled = true;
      break;
    }
    AT_TRY(check(cudaMemsetAsync(flag->get(), 0, sizeof(int), s), "cudaMemsetAsync(changed flag)"));
    AT_TRY(start->record(*stream));
    AT_TRY(graph->launch(*stream));
    AT_TRY(end->record(*stream));
    AT_TRY(check(cudaMemcpyAsync(flagHost->get(), flag->get(), sizeof(int), cudaMemcpyDeviceToHost, s),
                 "cudaMemcpyAsync(changed flag, device to host)"));
    AT_TRY(stream->synchronize());
    auto ms = end->millisecondsSince(*start);
    if (!ms) return tl::unexpected(ms.error());
    stats.msPerPass.push_back(*ms);
    stats.passesRun = pass + 1;
    lastChanged = *flagHost->get() != 0;
    if (control.progress) control.progress(pass + 1, planned);
    if (params.converge && !lastChanged) break;
  }
  AT_TRY(stream->synchronize());
  stats.converged = stats.passesRun > 0 && !lastChanged && !stats.cancelled;
  stats.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  auto impl = std::make_unique<DeviceField::Impl>();
  impl->grid = problem.grid;
  impl->downsample = params.downsample;
  impl->distances = std::move(*a);
  if (statsOut) *statsOut = std::move(stats);
  return DeviceField(std::move(impl));
}

Status copyToHost(const DeviceField& field, FloatVolume& out) {
  out.geometry = field.grid();
  out.voxels.resize(field.grid().dims.count());
  if (out.voxels.empty()) return {};
  return check(cudaMemcpy(out.voxels.data(), field.devicePointer(), out.voxels.size() * sizeof(float),
                          cudaMemcpyDeviceToHost),
               "cudaMemcpy(distances, device to host)");
}

Result<WdtResult> runCudaBackend(const WdtProblem& problem, const WdtControl& control) {
  const auto t0 = std::chrono::steady_clock::now();
  WdtResult result;
  auto field = runCudaBackendOnDevice(problem, control, &result.stats);
  if (!field) return tl::unexpected(field.error());
  AT_TRY(copyToHost(*field, result.field.distances));
  result.field.downsample = field->downsample();
  result.stats.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace at::cuda
