// The CUDA backend of the weighted distance transform. Nothing here exposes CUDA types: callers
// see plain C++ (the cuda/ folder is the only place that includes cuda_runtime.h).
//
// Each sweep is ceil(planes / 8) launches of overlapped plane groups (cuda/src/exact_sweep.cu);
// fields equal the CPU backend's bit for bit after any number of passes (and hence the exact
// reference once converged). Deterministic: no thread reads data written in the same launch by
// another block. A pass is replayed as one CUDA graph: progress and cancellation are per pass.
// Device buffers, staging memory and the captured pass are kept for the next call on a grid of
// the same size (the two most recent sizes: about 10 bytes of device memory per voxel each, held
// until the process ends or an allocation needs the memory).
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

// A float32 distance field that lives in device memory (for the renderer's CUDA–GL interop):
// grid().dims.count() floats, x contiguous, +infinity where unreachable. Move-only; frees its
// memory when destroyed.
class DeviceField {
 public:
  DeviceField();
  ~DeviceField();
  DeviceField(DeviceField&&) noexcept;
  DeviceField& operator=(DeviceField&&) noexcept;
  DeviceField(const DeviceField&) = delete;
  DeviceField& operator=(const DeviceField&) = delete;

  const Geometry& grid() const;
  int downsample() const;
  // Device address of the first voxel (a `const float*` in device code); null when empty.
  const void* devicePointer() const;

  struct Impl;

 private:
  explicit DeviceField(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  friend Result<DeviceField> makeDeviceField(const Geometry& grid, float fill);
  friend Result<DeviceField> runCudaBackendOnDevice(const WdtProblem&, const WdtControl&, WdtStats*);
};

// An allocated field on `grid` with every voxel set to `fill`. Errors: no device, allocation
// failure (message names the call and the byte count).
Result<DeviceField> makeDeviceField(const Geometry& grid, float fill);

// As runCudaBackend, but the field stays on the device. `stats` (optional) receives the run's
// statistics; their msTotal excludes the copy back.
Result<DeviceField> runCudaBackendOnDevice(const WdtProblem& problem, const WdtControl& control, WdtStats* stats);

// Copies the field into `out` (geometry and voxels replaced).
Status copyToHost(const DeviceField& field, FloatVolume& out);

}  // namespace at::cuda
