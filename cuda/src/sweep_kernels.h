// Launchers for the sweep kernels (exact_sweep.cu). Private to cuda/src.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>
#include <functional>

#include "core/error.h"
#include "wdt/stencil.h"
#include "wdt/wdt.h"

namespace at::cuda {

// Fills `d` (count floats) with 0 where seeds[i] != 0 and +infinity elsewhere.
Status launchInitDistances(float* d, const std::uint8_t* seeds, std::size_t count, cudaStream_t stream);

// Tiles whose sweeps may run as one persistent launch: none, the large tile only (the default:
// faster than its group launches on an H200, bench/RESULTS.md), or every tile.
enum class PersistentTiles { None, Large, All };

// One sweep: planes of nu × nv lanes (u contiguous, stride 1; v stride strideV), na planes of
// stride strideA, visited in `direction`. Reads `src` (the field before the sweep) and writes
// every voxel of `dst`, exactly as a serial sweep would; adds the number of voxels it lowered to
// *lowered.
struct ExactSweepArgs {
  const float* src = nullptr;
  float* dst = nullptr;
  const std::uint8_t* density = nullptr;  // densityByte per voxel, same layout as src
  int nu = 0, nv = 0, na = 0;
  std::size_t strideV = 0, strideA = 0;
  int direction = 1;
  wdt::SweepLengths lengths{};            // B = u, C = v (wdt::axisSweepLengths' plane order)
  float baseCost = 0;
  StepRule rule = StepRule::Entering;
  WeightRule weight = WeightRule::Density;
  unsigned long long* lowered = nullptr;
  // Which tiles run the sweep as one persistent launch (setPersistentSweeps) where all its blocks
  // fit the GPU at once; group launches elsewhere. progress: kSweepProgressCounters tile progress
  // counters (non-null unless persistent is None), zeroed by zeroProgress, which the launcher calls
  // before a persistent launch (the caller makes repeated calls in one pass cheap).
  PersistentTiles persistent = PersistentTiles::None;
  unsigned* progress = nullptr;
  std::function<Status()> zeroProgress;
  int* persistentLaunches = nullptr;  // optional: incremented when the sweep ran as one persistent launch
};
constexpr int kSweepProgressCounters = 1024;
Status launchExactSweep(const ExactSweepArgs& args, cudaStream_t stream);
// The sweep as one persistent launch (persistent_sweep.cu) of the one-wave tile or the large tile,
// if all its blocks fit the GPU at once; *launched says whether it did (false: the caller launches
// the plane groups instead).
Status launchPersistentSweep(const ExactSweepArgs& args, bool oneWaveTile, cudaStream_t stream, bool* launched);

// out[y + ny·(x + nx·z)] = in[x + nx·(y + ny·z)]: swaps the two fastest axes of an nx×ny×nz array.
template <class T>
Status launchTransposeXY(const T* in, T* out, int nx, int ny, int nz, cudaStream_t stream);

// Density bytes and seeds of one structure on a (possibly coarser) grid, from device-resident HU
// and labels: coarse voxel c takes the largest lut[HU + 32768] of its factor³ block of fine voxels
// and is a seed if any of them holds `label` (prepareWdtProblem's rules). Sets *anySeed to 1 if
// any voxel is a seed (the caller zeroes it first).
struct BuildProblemArgs {
  const std::int16_t* hu = nullptr;
  const std::uint16_t* labels = nullptr;
  const std::uint8_t* lut = nullptr;  // 65536 entries (densityTable)
  std::uint16_t label = 0;
  int factor = 1;
  struct { int x, y, z; } fine{0, 0, 0}, coarse{0, 0, 0};
  std::uint8_t* density = nullptr;
  std::uint8_t* seeds = nullptr;
  int* anySeed = nullptr;
};
Status launchBuildProblem(const BuildProblemArgs& args, cudaStream_t stream);

// Sets `count` floats at `d` to `value`.
Status launchFill(float* d, std::size_t count, float value, cudaStream_t stream);

}  // namespace at::cuda
