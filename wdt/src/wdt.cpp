// computeWdt: the front end. Prepares the problem and picks the backend:
//   cpu  → the CPU sweeps;
//   cuda → the CUDA backend (an error where this build has none or no device exists);
//   auto → CUDA when compiled in and a device is available, else the CPU; a CUDA failure under
//          auto falls back to the CPU and leaves a one-line reason in stats.warning.
// The rule itself is cpu_fallback.h's, shared with the field service.
#include <chrono>
#include <string>

#include "cpu_fallback.h"
#include "wdt/problem.h"
#include "wdt/wdt.h"

namespace at {

Result<WdtResult> computeWdt(const Volume& volume, const Mask& seeds, const WdtParams& params,
                             const WdtControl& control) {
  const auto t0 = std::chrono::steady_clock::now();
  auto problem = prepareWdtProblem(volume, seeds, params);
  if (!problem) return tl::unexpected(problem.error());

  std::string warning;
  Result<WdtResult> result = wdt::detail::withCpuFallback<WdtResult>(
      params.backend,
      [&] {
#if defined(AT_HAVE_CUDA)
        return cuda::runCudaBackend(*problem, control);
#else
        return Result<WdtResult>(fail(ErrorKind::Unavailable, "WDT: this build has no CUDA backend"));
#endif
      },
      [&] { return runCpuBackend(*problem, control); }, warning);
  if (!result) return result;
  result->stats.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!warning.empty()) result->stats.warning = warning;
  return result;
}

}  // namespace at
