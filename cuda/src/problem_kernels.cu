// The problem-building kernel of DeviceVolume: density bytes and seeds made on the device from
// the resident HU and label volumes, byte for byte what prepareWdtProblem makes on the host.
#include <cuda_runtime.h>

#include <cstdint>

#include "cuda_util.h"
#include "sweep_kernels.h"

namespace at::cuda {
namespace {

// One thread per coarse voxel: the maximum density byte over its block of fine voxels (blocks
// clipped at the volume's far faces) and whether any fine voxel carries `label`.
__global__ void buildProblem(BuildProblemArgs a) {
  const std::size_t count = std::size_t(a.coarse.x) * a.coarse.y * a.coarse.z;
  for (std::size_t c = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; c < count;
       c += std::size_t(gridDim.x) * blockDim.x) {
    const int ci = int(c % std::size_t(a.coarse.x));
    const int cj = int((c / std::size_t(a.coarse.x)) % std::size_t(a.coarse.y));
    const int ck = int(c / (std::size_t(a.coarse.x) * a.coarse.y));
    std::uint8_t q = 0;
    bool seed = false;
    for (int k = ck * a.factor; k < min((ck + 1) * a.factor, a.fine.z); ++k)
      for (int j = cj * a.factor; j < min((cj + 1) * a.factor, a.fine.y); ++j) {
        const std::size_t row = (std::size_t(k) * a.fine.y + j) * a.fine.x;
        for (int i = ci * a.factor; i < min((ci + 1) * a.factor, a.fine.x); ++i) {
          const std::uint8_t v = __ldg(a.lut + (int(__ldg(a.hu + row + i)) + 32768));
          q = v > q ? v : q;
          seed |= __ldg(a.labels + row + i) == a.label;
        }
      }
    a.density[c] = q;
    a.seeds[c] = seed ? 1 : 0;
    if (seed) *a.anySeed = 1;  // every writer stores the same value
  }
}

}  // namespace

Status launchBuildProblem(const BuildProblemArgs& args, cudaStream_t stream) {
  const std::size_t count = std::size_t(args.coarse.x) * args.coarse.y * args.coarse.z;
  if (count == 0) return {};
  const std::size_t blocks = (count + 255) / 256;
  buildProblem<<<unsigned(blocks < 16384 ? blocks : 16384), 256, 0, stream>>>(args);
  return check(cudaGetLastError(), "launch of the problem-building kernel");
}

}  // namespace at::cuda
