// The one rule for choosing the WDT backend, shared by computeWdt (wdt.cpp) and the field service
// (field_service.cpp), so that a change to the fallback is made once:
//   cpu  → the CPU;
//   cuda → the GPU; an Unavailable error where this build has no CUDA or no device exists;
//   auto → the GPU when CUDA is compiled in, a device exists and the caller has not seen it fail
//          (*gpuBroken), else the CPU. When the GPU fails, the CPU runs instead and `warning` says
//          why in one line; *gpuBroken is set so that a caller keeping state stays on the CPU.
#pragma once

#include <string>

#include "core/error.h"
#include "wdt/wdt.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/wdt_cuda.h"
#endif

namespace at::wdt::detail {

template <class T, class Gpu, class Cpu>
Result<T> withCpuFallback(WdtBackend backend, Gpu&& onGpu, Cpu&& onCpu, std::string& warning,
                          bool* gpuBroken = nullptr) {
#if defined(AT_HAVE_CUDA)
  const cuda::DeviceInfo& device = cuda::queryDevice();
  if (backend == WdtBackend::Cuda && !device.available)
    return fail(ErrorKind::Unavailable, "WDT: backend cuda requested but " +
                                            (device.reason.empty() ? std::string("no CUDA device is available")
                                                                   : device.reason));
  const bool broken = gpuBroken && *gpuBroken;
  if (backend == WdtBackend::Cuda || (backend == WdtBackend::Auto && device.available && !broken)) {
    Result<T> result = onGpu();
    if (result || backend == WdtBackend::Cuda) return result;
    if (gpuBroken) *gpuBroken = true;
    warning = "CUDA backend failed, computed on the CPU instead: " + result.error().message;
  }
  return onCpu();
#else
  (void)onGpu;
  (void)warning;
  (void)gpuBroken;
  if (backend == WdtBackend::Cuda) return fail(ErrorKind::Unavailable, "WDT: this build has no CUDA backend");
  return onCpu();
#endif
}

}  // namespace at::wdt::detail
