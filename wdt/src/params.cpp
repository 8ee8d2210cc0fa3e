// WdtParams: names of the enums (as the command line and presets spell them) and validation.
#include <cmath>
#include <string>

#include "wdt/wdt.h"

namespace at {

const char* toString(StepRule rule) {
  switch (rule) {
    case StepRule::Entering: return "entering";
    case StepRule::Trapezoid: return "trapezoid";
  }
  return "?";
}

const char* toString(WeightRule rule) {
  switch (rule) {
    case WeightRule::Density: return "density";
    case WeightRule::Uniform: return "uniform";
    case WeightRule::Gradient: return "gradient";
    case WeightRule::Ascent: return "ascent";
  }
  return "?";
}

const char* toString(WdtBackend backend) {
  switch (backend) {
    case WdtBackend::Auto: return "auto";
    case WdtBackend::Cpu: return "cpu";
    case WdtBackend::Cuda: return "cuda";
  }
  return "?";
}

Result<StepRule> parseStepRule(const std::string& text) {
  if (text == "entering") return StepRule::Entering;
  if (text == "trapezoid") return StepRule::Trapezoid;
  return fail("step rule: unknown '" + text + "' (use entering or trapezoid)");
}

Result<WeightRule> parseWeightRule(const std::string& text) {
  if (text == "density") return WeightRule::Density;
  if (text == "uniform") return WeightRule::Uniform;
  if (text == "gradient") return WeightRule::Gradient;
  if (text == "ascent") return WeightRule::Ascent;
  return fail("weight rule: unknown '" + text + "' (use density, uniform, gradient or ascent)");
}

Result<WdtBackend> parseBackend(const std::string& text) {
  if (text == "auto") return WdtBackend::Auto;
  if (text == "cpu") return WdtBackend::Cpu;
  if (text == "cuda") return WdtBackend::Cuda;
  return fail("backend: unknown '" + text + "' (use auto, cpu or cuda)");
}

Status validateWdtParams(const WdtParams& p) {
  if (p.passes < 1) return fail("WDT params: passes must be >= 1, got " + std::to_string(p.passes));
  if (p.maxPasses < 1) return fail("WDT params: maxPasses must be >= 1, got " + std::to_string(p.maxPasses));
  if (p.downsample < 1)
    return fail("WDT params: downsample must be >= 1, got " + std::to_string(p.downsample));
  if (!std::isfinite(p.huMin) || !std::isfinite(p.huMax) || !(p.huMax > p.huMin))
    return fail("WDT params: HU window must have huMax > huMin, got " + std::to_string(p.huMin) + ".." +
                std::to_string(p.huMax));
  if (!std::isfinite(p.baseCost) || p.baseCost < 0)
    return fail("WDT params: baseCost must be >= 0, got " + std::to_string(p.baseCost));
  return {};
}

}  // namespace at
