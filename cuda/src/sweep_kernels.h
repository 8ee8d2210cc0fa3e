// Launchers for the sweep kernels (exact_sweep.cu). Private to cuda/src.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "volume/error.h"
#include "wdt/stencil.h"
#include "wdt/wdt.h"

namespace at::cuda {

// Fills `d` (count floats) with 0 where seeds[i] != 0 and +infinity elsewhere.
Status launchInitDistances(float* d, const std::uint8_t* seeds, std::size_t count, cudaStream_t stream);

// One sweep: planes of nu × nv lanes (u stride strideU, v stride strideV), na planes of stride
// strideA, visited in `direction`. Reads `src` (the field before the sweep) and writes every voxel
// of `dst`, exactly as a serial sweep would; sets *changed to 1 if any voxel decreased.
struct ExactSweepArgs {
  const float* src = nullptr;
  float* dst = nullptr;
  const std::uint8_t* density = nullptr;  // densityByte per voxel, same layout as src
  int nu = 0, nv = 0, na = 0;
  std::size_t strideU = 1, strideV = 0, strideA = 0;
  int direction = 1;
  wdt::SweepLengths lengths{};            // B = u, C = v (wdt::axisSweepLengths' plane order)
  float baseCost = 0;
  StepRule rule = StepRule::Entering;
  WeightRule weight = WeightRule::Density;
  unsigned* sync = nullptr;               // sweepSyncWords(args) words, zero before the launch
  int* changed = nullptr;
};
Status launchExactSweep(const ExactSweepArgs& args, cudaStream_t stream);
// Words of zeroed device memory a sweep needs for its scheduling (ticket counter, per-tile progress).
int sweepSyncWords(const ExactSweepArgs& args);
// Once per process, before the first launchExactSweep (and outside stream capture): raises the
// kernels' shared memory limit and measures how many blocks fit on the device at once.
Status prepareExactSweeps();

// Sets `count` floats at `d` to `value`.
Status launchFill(float* d, std::size_t count, float value, cudaStream_t stream);

}  // namespace at::cuda
