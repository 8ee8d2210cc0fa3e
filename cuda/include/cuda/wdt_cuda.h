// The CUDA backend of the weighted distance transform. Nothing here exposes CUDA types: callers
// see plain C++ (the cuda/ folder is the only place that includes cuda_runtime.h).
//
// Each sweep is ceil(planes / 8) launches of overlapped plane groups (cuda/src/exact_sweep.cu);
// fields equal the CPU backend's bit for bit after any number of passes (and hence the exact
// reference once converged). Deterministic: no thread reads data written in the same launch by
// another block. A pass is replayed as one CUDA graph: progress and cancellation are per pass.
// Converge mode runs rounds over 16³ bricks that follow what still changes, from the seeds on grids
// of up to 128³ voxels and after two or three passes on larger ones (see
// setConvergeSweepsBeforeBricks).
// The rounds are one kernel, cancellable only before they start, and need one more field-sized
// device buffer (if it cannot be allocated, converge mode runs passes only).
// Device buffers, staging memory and the captured pass are kept for the next call on a grid of
// the same size (the two most recent sizes: about 10 bytes of device memory per voxel each, held
// until the process ends or an allocation needs the memory).
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "core/error.h"
#include "wdt/problem.h"

namespace at::cuda {

struct DeviceInfo {
  bool available = false;
  std::string name;      // "NVIDIA H100 80GB HBM3"
  std::string reason;    // why not available ("no CUDA device", "driver too old: …")
};

// Queries device 0 once per process (cached).
const DeviceInfo& queryDevice();

// Memory in use on device 0 (MiB: cudaMemGetInfo's total minus free, every process's), or −1 when
// there is no device or the query fails. For benchmarks that state what a size needs.
double deviceMemoryUsedMiB();

// Converge mode runs this many whole-volume passes, then brick rounds that finish the bricks still
// changing (cuda/src/brick_solver.h); the field is the same fixed point either way. Negative: the
// default, 0 on grids of up to 128³ voxels; above, 2, and a third when the second pass still
// lowered more than 1.15 values per voxel (measured on an H100, bench/RESULTS.md).
// Process-wide, for tests and benchmarks.
void setConvergeSweepsBeforeBricks(int passes);

// The sweep kernel of a pass: ceil(planes / K) group launches, or one persistent launch a sweep
// whose tiles walk the plane groups themselves, each waiting on its 8 neighbouring tiles' progress
// counters (cooperative launch: used only where every block of the sweep fits the GPU at once,
// e.g. up to 512³ on an H200; group launches elsewhere). The same field bit for bit either way.
// On: persistent wherever it fits; Off: group launches only; Auto (the default): persistent for
// the large tile only (planes whose default tiles need more than one wave, e.g. 512³ on an H200),
// where it was measured faster (bench/RESULTS.md). Process-wide, for tests and benchmarks; while
// Auto, the environment's AT_WDT_CUDA_PERSISTENT=1 or 0 means On or Off.
enum class PersistentSweeps { Auto = -1, Off = 0, On = 1 };
void setPersistentSweeps(PersistentSweeps mode);
inline void setPersistentSweeps(bool on) { setPersistentSweeps(on ? PersistentSweeps::On : PersistentSweeps::Off); }
// Sweeps captured as persistent launches since the process started (a pass is captured once per
// grid size and parameters, then replayed): whether the persistent kernel ran.
long long persistentSweepsCaptured();

// Computes the field on the GPU and copies it back. Errors carry the failing CUDA call's name and
// message; the caller (computeWdt with backend auto) then falls back to the CPU.
Result<WdtResult> runCudaBackend(const WdtProblem& problem, const WdtControl& control);

class DeviceVolume;

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
  friend Result<DeviceField> runCudaBackendOnDevice(const DeviceVolume&, std::uint16_t, const WdtParams&,
                                                    const WdtControl&, WdtStats*);
};

// An allocated field on `grid` with every voxel set to `fill`. Errors: no device, allocation
// failure (message names the call and the byte count).
Result<DeviceField> makeDeviceField(const Geometry& grid, float fill);

// As runCudaBackend, but the field stays on the device. `stats` (optional) receives the run's
// statistics; their msTotal excludes the copy back.
Result<DeviceField> runCudaBackendOnDevice(const WdtProblem& problem, const WdtControl& control, WdtStats* stats);

// A CT volume and its label map kept in device memory (4 bytes per voxel), so that repeated
// fields on the same data — hovering from structure to structure — upload nothing: each request's
// density bytes and seeds are made on the device, byte for byte what prepareWdtProblem makes on
// the host (downsampling included), so the fields equal runCudaBackend's bit for bit. Calls on one
// DeviceVolume are serialised (it caches the density table of the last HU window). Move-only;
// frees its memory when destroyed.
class DeviceVolume {
 public:
  DeviceVolume();
  ~DeviceVolume();
  DeviceVolume(DeviceVolume&&) noexcept;
  DeviceVolume& operator=(DeviceVolume&&) noexcept;
  DeviceVolume(const DeviceVolume&) = delete;
  DeviceVolume& operator=(const DeviceVolume&) = delete;

  const Geometry& grid() const;

  struct Impl;

 private:
  explicit DeviceVolume(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  friend Result<DeviceVolume> uploadVolume(const Volume&, const LabelMap&);
  friend Result<DeviceField> runCudaBackendOnDevice(const DeviceVolume&, std::uint16_t, const WdtParams&,
                                                    const WdtControl&, WdtStats*);
};

// Copies `volume` and `labels` (same dims) to the device. Errors: no device, mismatched or empty
// grids, allocation failure.
Result<DeviceVolume> uploadVolume(const Volume& volume, const LabelMap& labels);

// The field of the structure `label` (its voxels are the seeds) on `volume` with `params`, left
// on the device. Errors as runCudaBackend, and "no voxel carries label N" for an absent structure.
Result<DeviceField> runCudaBackendOnDevice(const DeviceVolume& volume, std::uint16_t label, const WdtParams& params,
                                           const WdtControl& control, WdtStats* stats);

// Copies the field into `out` (geometry and voxels replaced).
Status copyToHost(const DeviceField& field, FloatVolume& out);

}  // namespace at::cuda
