// The converge-mode solver of the CUDA backend (brick_solver.cu). Private to cuda/src.
#pragma once

#include <cuda_runtime.h>

#include <cstdint>

#include "core/error.h"
#include "wdt/wdt.h"

namespace at::cuda {

// Device buffers the brick solver works in, owned by the caller (the Workspace). `field` holds the
// distances (x contiguous, nx × ny × nz); `shell[0]` and `shell[1]` are two more fields of the same
// size; `flags` and `lists` hold 2 × brickCount(dims) ints each; `counters` holds 3 ints and
// `result` 2.
struct BrickSolveBuffers {
  float* field = nullptr;
  const std::uint8_t* density = nullptr;  // densityByte per voxel, x contiguous
  float* shell[2] = {nullptr, nullptr};
  int* flags = nullptr;
  int* lists = nullptr;
  int* counters = nullptr;
  int* result = nullptr;  // after launchBrickSolve: [0] rounds run, [1] bricks still active
};

// Edge of the bricks, in voxels.
constexpr int kBrickEdge = 16;

// Bricks of kBrickEdge³ voxels covering the grid.
std::size_t brickCount(int nx, int ny, int nz);

struct BrickSolveParams {
  float spacing[3] = {1, 1, 1};
  float baseCost = 0;
  StepRule rule = StepRule::Entering;
  WeightRule weight = WeightRule::Density;
  int maxRounds = 1;
};

// Relaxes `field` (any field at or above the fixed point: the initial one, or one after some
// whole-volume passes) to the fixed point of the 26-neighbour step costs, equal to the converged
// sweeps and to the exact reference. A start kernel copies the field's brick-boundary voxels into
// both halo snapshots and queues every brick holding a voxel that a neighbour can still lower;
// then one cooperative kernel runs rounds: each active brick sweeps its voxels once x+ x− y+ y−
// z+ z− (the sweeps' plane updates, on the brick and a one-voxel halo), queues the bricks next to
// any boundary voxel that decreased, and queues itself again if anything decreased. Stops when no
// brick is active or after maxRounds rounds; writes rounds run and bricks still active to result.
Status launchBrickSolve(const BrickSolveBuffers& b, int nx, int ny, int nz, const BrickSolveParams& params,
                        cudaStream_t stream);

}  // namespace at::cuda
