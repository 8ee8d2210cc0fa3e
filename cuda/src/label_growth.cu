// The CUDA engine of the multi-label growth (cuda/label_growth_cuda.h).
//
// The kernels are label_growth_kernels.cuh's; here the engine: device state kept between updates,
// launches, statistics.
#include "cuda/label_growth_cuda.h"

#include <cuda_runtime.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "cuda/wdt_cuda.h"
#include "cuda_util.h"
#include "label_growth_kernels.cuh"
#include "growth_local_reset.cuh"
#include "wdt/step_cost.h"

namespace at::cuda {
namespace {

class CudaGrowthEngine final : public GrowthEngine {
 public:
  static Result<std::unique_ptr<GrowthEngine>> create(const GrowthProblem& problem) {
    const Dims d = problem.grid.dims;
    if (d.count() == 0 || problem.density.size() != d.count())
      return fail("CUDA growth: problem arrays do not match the grid " + d.toString());
    if (d.count() >= (std::size_t(1) << 32)) return fail("CUDA growth: the grid " + d.toString() + " is too large");
    if (!queryDevice().available) return fail("CUDA growth: " + queryDevice().reason);
    AT_TRY(check(cudaSetDevice(0), "cudaSetDevice(0)"));
    auto e = std::unique_ptr<CudaGrowthEngine>(new CudaGrowthEngine);
    e->grid_ = problem.grid;
    e->kernel_ = problem.kernel;
    e->base_ = problem.baseCost;
    e->scale_ = problem.scale;
    GridShape& g = e->shape_;
    g.n[0] = d.x, g.n[1] = d.y, g.n[2] = d.z;
    for (int i = 0; i < 3; ++i) g.bricks[i] = (g.n[i] + kEdge - 1) / kEdge;
    const int bricks = g.bricks[0] * g.bricks[1] * g.bricks[2];
    AT_ASSIGN(e->stream_, Stream::create());
    AT_ASSIGN(e->keys_, DeviceBuffer<unsigned long long>::allocate(d.count()));
    AT_ASSIGN(e->density_, DeviceBuffer<std::uint8_t>::allocate(d.count()));
    AT_ASSIGN(e->flags_, DeviceBuffer<int>::allocate(2 * std::size_t(bricks)));
    AT_ASSIGN(e->lists_, DeviceBuffer<int>::allocate(2 * std::size_t(bricks)));
    AT_ASSIGN(e->brickKeys_, DeviceBuffer<int>::allocate(2 * std::size_t(bricks)));
    AT_ASSIGN(e->visitList_, DeviceBuffer<int>::allocate(std::size_t(bricks)));
    AT_ASSIGN(e->counters_, DeviceBuffer<int>::allocate(kCounters));
    AT_ASSIGN(e->countersHost_, PinnedBuffer<int>::allocate(kCounters));
    AT_ASSIGN(e->resetBits_, DeviceBuffer<unsigned>::allocate(65536 / 32));
    AT_ASSIGN(e->start_, Event::create());
    AT_ASSIGN(e->end_, Event::create());
    const cudaStream_t s = e->stream_.get();
    AT_TRY(check(cudaMemcpyAsync(e->density_.get(), problem.density.data(), d.count(), cudaMemcpyHostToDevice, s),
                 "cudaMemcpyAsync(density, host to device)"));
    AT_TRY(check(cudaMemsetAsync(e->flags_.get(), 0, e->flags_.bytes(), s), "cudaMemsetAsync(brick flags)"));
    AT_TRY(check(cudaMemsetAsync(e->brickKeys_.get(), 0x7F, e->brickKeys_.bytes(), s), "cudaMemsetAsync(brick keys)"));
    AT_TRY(check(cudaMemsetAsync(e->counters_.get(), 0, e->counters_.bytes(), s), "cudaMemsetAsync(growth counters)"));
    AT_TRY(e->stream_.synchronize());
    e->queues_.brickCount = bricks;
    e->queues_.flags = e->flags_.get();
    e->queues_.lists = e->lists_.get();
    e->queues_.keys = e->brickKeys_.get();
    e->queues_.visitList = e->visitList_.get();
    e->queues_.counters = e->counters_.get();
    return std::unique_ptr<GrowthEngine>(std::move(e));
  }

  Status apply(const GrowthChange& change, const WdtControl& control, GrowthStats& stats) override {
    const cudaStream_t s = stream_.get();
    const std::size_t n = grid_.dims.count();
    stats.backendUsed = WdtBackend::Cuda;
    stats.device = queryDevice().name;
    AT_TRY(check(cudaSetDevice(0), "cudaSetDevice(0)"));
    AT_TRY(start_.record(stream_));
    // Counters 0 … 2 hold the queue: empty after a finished solve, the pending list 0 after a
    // cancelled one. The statistics start from 0.
    AT_TRY(check(cudaMemsetAsync(counters_.get() + 3, 0, (kMinKeyCounter - 3) * sizeof(int), s),
                 "cudaMemsetAsync(growth statistics)"));
    AT_TRY(check(cudaMemsetAsync(counters_.get() + kMinKeyCounter, 0x7F, 3 * sizeof(int), s),
                 "cudaMemsetAsync(growth round keys)"));
    AT_TRY(check(cudaMemsetAsync(counters_.get() + kVisitCounter, 0, 3 * sizeof(int), s),
                 "cudaMemsetAsync(growth round visits)"));
    if (change.fromScratch) {
      fillKeys<<<gridBlocks(n), 256, 0, s>>>(keys_.get(), n, wdt::packGrowthKey(kInf, wdt::kNoLabel));
      AT_TRY(check(cudaGetLastError(), "launch of the key fill kernel"));
    } else if (!change.resetLabels.empty()) {
      std::vector<unsigned> bits(65536 / 32, 0);
      for (std::uint16_t l : change.resetLabels) bits[l >> 5] |= 1u << (l & 31);
      AT_TRY(check(cudaMemcpyAsync(resetBits_.get(), bits.data(), resetBits_.bytes(), cudaMemcpyHostToDevice, s),
                   "cudaMemcpyAsync(reset labels, host to device)"));
      AT_TRY(stream_.synchronize());  // `bits` leaves scope
      resetLabels<<<gridBlocks(n), 256, 0, s>>>(keys_.get(), shape_, resetBits_.get(), queues_);
      AT_TRY(check(cudaGetLastError(), "launch of the label reset kernel"));
    }
    if (!change.fromScratch && !change.removedSeeds.empty()) AT_TRY(resetGrownFrom(change.removedSeeds));
    if (!change.writeSeeds.empty()) {
      const std::size_t count = change.writeSeeds.size();
      std::vector<unsigned> index(count);
      std::vector<int> label(count);
      for (std::size_t i = 0; i < count; ++i) {
        index[i] = unsigned(change.writeSeeds[i].index);
        label[i] = change.writeSeeds[i].label;
      }
      if (seedIndex_.size() < count) {
        AT_ASSIGN(seedIndex_, DeviceBuffer<unsigned>::allocate(count));
        AT_ASSIGN(seedLabel_, DeviceBuffer<int>::allocate(count));
      }
      AT_TRY(check(cudaMemcpyAsync(seedIndex_.get(), index.data(), count * sizeof(unsigned), cudaMemcpyHostToDevice, s),
                   "cudaMemcpyAsync(seed voxels, host to device)"));
      AT_TRY(check(cudaMemcpyAsync(seedLabel_.get(), label.data(), count * sizeof(int), cudaMemcpyHostToDevice, s),
                   "cudaMemcpyAsync(seed labels, host to device)"));
      writeSeeds<<<gridBlocks(count), 256, 0, s>>>(keys_.get(), shape_, seedIndex_.get(), seedLabel_.get(), int(count),
                                                   queues_);
      AT_TRY(check(cudaGetLastError(), "launch of the seed kernel"));
      AT_TRY(stream_.synchronize());  // `index` and `label` leave scope
    }
    // Cancellation is looked at before the rounds (they take milliseconds); the queued bricks then
    // stay in list 0 for the next update.
    stats.cancelled = control.cancel && control.cancel->load(std::memory_order_relaxed);
    if (!stats.cancelled) {
      AT_TRY(solve());
      // Solved to the end: every flag is 0 again; so must the list lengths be for the next update.
      AT_TRY(check(cudaMemsetAsync(counters_.get(), 0, 3 * sizeof(int), s), "cudaMemsetAsync(growth queue)"));
    }
    AT_TRY(end_.record(stream_));
    AT_TRY(check(cudaMemcpyAsync(countersHost_.get(), counters_.get(), kCounters * sizeof(int), cudaMemcpyDeviceToHost, s),
                 "cudaMemcpyAsync(growth counters, device to host)"));
    AT_TRY(stream_.synchronize());
    const int* c = countersHost_.get();
    stats.rounds = c[3];
    stats.converged = !stats.cancelled && c[4] == 0;
    stats.brickVisits += std::size_t(c[5]);
    stats.voxelsReset = std::size_t(c[6]);
    auto ms = end_.millisecondsSince(start_);
    if (!ms) return tl::unexpected(ms.error());
    stats.msCompute = *ms;
    return {};
  }

  bool resetsGrownFromRemovedSeeds() const override { return true; }

  Status readLabels(LabelMap& out) override {
    const std::size_t n = grid_.dims.count();
    if (labelsOut_.size() != n) AT_ASSIGN(labelsOut_, DeviceBuffer<std::uint16_t>::allocate(n));
    keysToLabels<<<gridBlocks(n), 256, 0, stream_.get()>>>(keys_.get(), labelsOut_.get(), n);
    AT_TRY(check(cudaGetLastError(), "launch of the label read-back kernel"));
    out.geometry = grid_;
    out.voxels.resize(n);
    AT_TRY(check(cudaMemcpyAsync(out.voxels.data(), labelsOut_.get(), n * sizeof(std::uint16_t), cudaMemcpyDeviceToHost,
                                 stream_.get()),
                 "cudaMemcpyAsync(labels, device to host)"));
    return stream_.synchronize();
  }

  Status readDistances(FloatVolume& out) override {
    const std::size_t n = grid_.dims.count();
    DeviceBuffer<float> distances;
    AT_ASSIGN(distances, DeviceBuffer<float>::allocate(n));
    keysToDistances<<<gridBlocks(n), 256, 0, stream_.get()>>>(keys_.get(), distances.get(), n, scale_);
    AT_TRY(check(cudaGetLastError(), "launch of the distance read-back kernel"));
    out.geometry = grid_;
    out.voxels.resize(n);
    AT_TRY(check(cudaMemcpyAsync(out.voxels.data(), distances.get(), n * sizeof(float), cudaMemcpyDeviceToHost,
                                 stream_.get()),
                 "cudaMemcpyAsync(distances, device to host)"));
    return stream_.synchronize();
  }

 private:
  CudaGrowthEngine() = default;

  // GrowthChange::removedSeeds (growth_local_reset.cuh): the voxels whose pair came from them,
  // found on the old pairs, then reset and their bricks queued. The first call allocates a list of
  // every voxel and a bit each (4.125 bytes a voxel, kept for later edits).
  Status resetGrownFrom(const std::vector<GrowthSeed>& removed) {
    const cudaStream_t s = stream_.get();
    const std::size_t n = grid_.dims.count();
    if (foundCount_.size() != 1) {  // allocated last: after a failed allocation all three are again
      AT_ASSIGN(foundList_, DeviceBuffer<unsigned>::allocate(n));
      AT_ASSIGN(foundBits_, DeviceBuffer<unsigned>::allocate(n / 32 + 1));
      AT_ASSIGN(foundCount_, DeviceBuffer<unsigned>::allocate(1));
    }
    AT_TRY(check(cudaMemsetAsync(foundBits_.get(), 0, foundBits_.bytes(), s), "cudaMemsetAsync(found voxels)"));
    AT_TRY(check(cudaMemsetAsync(foundCount_.get(), 0, sizeof(unsigned), s), "cudaMemsetAsync(found count)"));
    const std::size_t count = removed.size();
    std::vector<unsigned> index(count);
    for (std::size_t i = 0; i < count; ++i) index[i] = unsigned(removed[i].index);
    if (removedIndex_.size() < count) AT_ASSIGN(removedIndex_, DeviceBuffer<unsigned>::allocate(count));
    AT_TRY(check(cudaMemcpyAsync(removedIndex_.get(), index.data(), count * sizeof(unsigned), cudaMemcpyHostToDevice, s),
                 "cudaMemcpyAsync(removed seeds, host to device)"));
    FoundVoxels f{foundBits_.get(), foundList_.get(), foundCount_.get()};
    markRemovedSeeds<<<gridBlocks(count), 256, 0, s>>>(removedIndex_.get(), int(count), f);
    AT_TRY(check(cudaGetLastError(), "launch of the removed-seed kernel"));
    AT_TRY(stream_.synchronize());  // `index` leaves scope
    int device = 0, sms = 0;
    AT_TRY(check(cudaGetDevice(&device), "cudaGetDevice"));
    AT_TRY(check(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device), "cudaDeviceGetAttribute(SM count)"));
    AT_TRY(wdt::withCostKernel(kernel_, [&]<CostKernel K>() -> Status {
      auto* kernel = findGrownFromRemoved<K>;
      int perSm = 0;
      AT_TRY(check(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&perSm, kernel, 256, 0),
                   "cudaOccupancyMaxActiveBlocksPerMultiprocessor(local reset kernel)"));
      if (perSm < 1) return fail("CUDA growth: the local reset kernel's blocks do not fit on a multiprocessor");
      const unsigned long long* keys = keys_.get();
      const std::uint8_t* density = density_.get();
      GridShape g = shape_;
      float sx = float(grid_.spacingMm[0]), sy = float(grid_.spacingMm[1]), sz = float(grid_.spacingMm[2]);
      float base = base_, scale = scale_;
      void* params[] = {&keys, &density, &g, &sx, &sy, &sz, &base, &scale, &f};
      // Four blocks a multiprocessor at most (32 listed voxels each at once): most levels are small
      // next to a grid barrier's cost. AT_CUDA_GROWTH_RESET_BLOCKS=N sets N (for comparisons).
      int perSmUsed = std::min(perSm, 4);
      if (const char* v = std::getenv("AT_CUDA_GROWTH_RESET_BLOCKS")) perSmUsed = std::clamp(std::atoi(v), 1, perSm);
      return check(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(kernel), dim3(unsigned(perSmUsed * sms)),
                                               dim3(256), params, 0, s),
                   "cudaLaunchCooperativeKernel(local reset kernel)");
    }));
    resetFound<<<unsigned(4 * sms), 256, 0, s>>>(keys_.get(), shape_, f, queues_);
    return check(cudaGetLastError(), "launch of the found-voxel reset kernel");
  }

  Status solve() {
    SolveArgs a{};
    a.keys = keys_.get();
    a.density = density_.get();
    a.g = shape_;
    a.q = queues_;
    const float sx = float(grid_.spacingMm[0]), sy = float(grid_.spacingMm[1]), sz = float(grid_.spacingMm[2]);
    for (int axis = 0; axis < 3; ++axis) a.lengths[axis] = wdt::axisSweepLengths(axis, sx, sy, sz);
    a.base = base_;
    a.scale = scale_;
    a.maxRounds = 1 << 30;
    // Ordered rounds; the first window: the cost of crossing a brick along an axis at the lowest
    // cost per mm (wdt::weightRange). AT_CUDA_GROWTH_ORDER=0 visits every queued brick in every
    // round; =F,M sets fewVisits and manyVisits (for comparisons on one machine).
    float lo = 0, hi = 0;
    const float shortest = std::min({sx, sy, sz});
    wdt::weightRange(kernel_, base_, shortest, lo, hi);
    a.window0 = int(std::clamp(double(lo) * shortest * kEdge * double(scale_), 1.0, double(1 << 30)));
    a.ordered = true;
    a.fewVisits = 4;
    a.manyVisits = 16;
    if (const char* v = std::getenv("AT_CUDA_GROWTH_ORDER")) {
      int few = 0, many = 0;
      if (std::string(v) == "0") a.ordered = false;
      else if (std::sscanf(v, "%d,%d", &few, &many) == 2 && few >= 0 && many > few)
        a.fewVisits = few, a.manyVisits = many;
    }
    return wdt::withCostKernel(kernel_, [&]<CostKernel K>() -> Status {
      auto* kernel = solveGrowth<K>;
      const int smem = int(sizeof(GrowthShared));
      AT_TRY(check(cudaFuncSetAttribute(reinterpret_cast<const void*>(kernel), cudaFuncAttributeMaxDynamicSharedMemorySize, smem),
                   "cudaFuncSetAttribute(growth kernel shared memory)"));
      int device = 0, sms = 0, perSm = 0;
      AT_TRY(check(cudaGetDevice(&device), "cudaGetDevice"));
      AT_TRY(check(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device), "cudaDeviceGetAttribute(SM count)"));
      AT_TRY(check(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&perSm, kernel, kThreads, std::size_t(smem)),
                   "cudaOccupancyMaxActiveBlocksPerMultiprocessor(growth kernel)"));
      if (perSm < 1) return fail("CUDA growth: the kernel's blocks do not fit on a multiprocessor");
      // Every block must be resident for the grid barrier.
      const int blocks = std::min(queues_.brickCount, perSm * sms);
      void* params[] = {&a};
      return check(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(kernel), dim3(unsigned(blocks)),
                                               dim3(kThreads), params, std::size_t(smem), stream_.get()),
                   "cudaLaunchCooperativeKernel(growth kernel)");
    });
  }

  Geometry grid_;
  CostKernel kernel_ = CostKernel::EdgeGradient;
  float base_ = 0;
  float scale_ = 1;
  GridShape shape_{};
  Queues queues_{};
  Stream stream_;
  DeviceBuffer<unsigned long long> keys_;
  DeviceBuffer<std::uint8_t> density_;
  DeviceBuffer<int> flags_, lists_, brickKeys_, visitList_, counters_;
  PinnedBuffer<int> countersHost_;
  DeviceBuffer<unsigned> resetBits_;
  DeviceBuffer<unsigned> seedIndex_;
  DeviceBuffer<int> seedLabel_;
  DeviceBuffer<std::uint16_t> labelsOut_;
  DeviceBuffer<unsigned> foundList_, foundBits_, foundCount_, removedIndex_;
  Event start_, end_;
};

}  // namespace

Result<std::unique_ptr<GrowthEngine>> makeCudaGrowthEngine(const GrowthProblem& problem) {
  return CudaGrowthEngine::create(problem);
}

}  // namespace at::cuda
