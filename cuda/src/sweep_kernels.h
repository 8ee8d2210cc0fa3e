// Launchers for the sweep kernels (sweep_kernels.cu). Private to cuda/src.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "volume/error.h"
#include "wdt/wdt.h"

namespace at::cuda {

// One sweep of the distance volume: reads `src` (never written during the sweep), writes every
// voxel of `dst`. Sets *changed to 1 if any voxel decreased. Volumes are nx·ny·nz, x contiguous.
struct SweepArgs {
  const float* src = nullptr;
  float* dst = nullptr;
  const std::uint8_t* density = nullptr;  // densityByte per voxel
  int nx = 0, ny = 0, nz = 0;
  float spacing[3] = {1, 1, 1};           // mm along x, y, z
  float baseCost = 0;
  StepRule rule = StepRule::Entering;
  WeightRule weight = WeightRule::Density;
  int* changed = nullptr;                 // device flag
};

// axis 0 = x, 1 = y, 2 = z; direction +1 (increasing index) or -1.
Status launchSweep(const SweepArgs& args, int axis, int direction, cudaStream_t stream);

// Fills `d` (count floats) with 0 where seeds[i] != 0 and +infinity elsewhere.
Status launchInitDistances(float* d, const std::uint8_t* seeds, std::size_t count, cudaStream_t stream);

// Sets `count` floats at `d` to `value`.
Status launchFill(float* d, std::size_t count, float value, cudaStream_t stream);

}  // namespace at::cuda
