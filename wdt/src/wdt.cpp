// computeWdt: the front end. Prepares the problem and picks the backend:
//   cpu  → the CPU sweeps;
//   cuda → the CUDA backend (an error where this build has none or no device exists);
//   auto → CUDA when compiled in and a device is available, else the CPU; a CUDA failure under
//          auto falls back to the CPU and leaves a one-line reason in stats.warning.
#include <chrono>
#include <string>

#include "wdt/problem.h"
#include "wdt/wdt.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/wdt_cuda.h"
#endif

namespace at {

Result<WdtResult> computeWdt(const Volume& volume, const Mask& seeds, const WdtParams& params,
                             const WdtControl& control) {
  const auto t0 = std::chrono::steady_clock::now();
  auto problem = prepareWdtProblem(volume, seeds, params);
  if (!problem) return tl::unexpected(problem.error());

  std::string warning;
  Result<WdtResult> result = fail("WDT: no backend ran");
#if defined(AT_HAVE_CUDA)
  const bool useCuda = params.backend == WdtBackend::Cuda ||
                       (params.backend == WdtBackend::Auto && cuda::queryDevice().available);
  if (params.backend == WdtBackend::Cuda && !cuda::queryDevice().available)
    return fail(ErrorKind::Unavailable, "WDT: backend cuda requested but " +
                (cuda::queryDevice().reason.empty() ? std::string("no CUDA device is available")
                                                    : cuda::queryDevice().reason));
  if (useCuda) {
    result = cuda::runCudaBackend(*problem, control);
    if (!result) {
      if (params.backend == WdtBackend::Cuda) return tl::unexpected(result.error());
      warning = "CUDA backend failed, computed on the CPU instead: " + result.error().message;
    }
  }
  if (!useCuda || !result) result = runCpuBackend(*problem, control);
#else
  if (params.backend == WdtBackend::Cuda) return fail(ErrorKind::Unavailable, "WDT: this build has no CUDA backend");
  result = runCpuBackend(*problem, control);
#endif
  if (!result) return result;
  result->stats.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!warning.empty()) result->stats.warning = warning;
  return result;
}

}  // namespace at
