// The CUDA backend of the weighted distance transform. Nothing here exposes CUDA types: callers
// see plain C++ (the cuda/ folder is the only place that includes cuda_runtime.h).
#pragma once

#include <memory>
#include <string>

#include "volume/error.h"
#include "wdt/problem.h"

namespace at::cuda {

struct DeviceInfo {
  bool available = false;
  std::string name;      // "NVIDIA H100 80GB HBM3"
  std::string reason;    // why not available ("no CUDA device", "driver too old: …")
};

// Queries device 0 once per process (cached).
const DeviceInfo& queryDevice();

// Computes the field on the GPU and copies it back. Errors carry the failing CUDA call's name and
// message; the caller (computeWdt with backend auto) then falls back to the CPU.
Result<WdtResult> runCudaBackend(const WdtProblem& problem, const WdtControl& control);

}  // namespace at::cuda
