// The intensity model: the unit of a loaded image, the window of plain intensities, and the
// label-map test of `info` (volume/intensity.h).
#include "volume/intensity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <limits>

#include "core/printable_text.h"
#include "volume/structure_forms.h"

namespace at {

bool isAttenuationModality(const std::string& modality) {
  // DICOM PS3.3 C.7.3.1.1.1: CT and the X-ray modalities (projection, angiography, mammography,
  // intra-oral, panoramic, radiographic imaging, digital fluoroscopy); OT (other) is unknown, so no
  // note is given for it.
  static const char* const kXRay[] = {"CT", "CR", "DX", "DF", "DS", "MG", "XA", "RF", "RG", "IO", "PX", "OT"};
  if (modality.empty()) return true;
  return std::any_of(std::begin(kXRay), std::end(kXRay), [&](const char* code) { return modality == code; });
}

bool IntensityModel::attenuationLike() const { return isAttenuationModality(modality); }

Result<std::string> parseModalityCode(const std::string& text) {
  std::string code = text;
  for (char& c : code)
    if (c >= 'a' && c <= 'z') c = char(c - 'a' + 'A');
  if (!isDicomModalityCode(code))
    return fail("modality: '" + printableText(text, 40) +
                "' is not a DICOM modality code (CT, MR, PT, US, …: 1 to 16 of A-Z, 0-9, '_' and ' ')");
  return code;
}

Result<IntensityChoice> parseIntensityChoice(const std::string& text) {
  if (text == "auto") return IntensityChoice::Auto;
  if (text == "hu") return IntensityChoice::Hounsfield;
  if (text == "plain") return IntensityChoice::Plain;
  return fail("intensity: unknown '" + text + "' (use auto, hu or plain)");
}

const char* intensityChoiceName(IntensityChoice choice) {
  switch (choice) {
    case IntensityChoice::Auto: return "auto";
    case IntensityChoice::Hounsfield: return "hu";
    case IntensityChoice::Plain: return "plain";
  }
  return "auto";
}

Status checkRescale(double intercept, double slope) {
  if (!(std::fabs(intercept) <= kRescaleInterceptLimit))
    return fail(std::string("--intercept: must be a number within ±") + kRescaleInterceptLimitText);
  if (!(std::fabs(slope) <= kRescaleSlopeLimit) || slope == 0)
    return fail(std::string("--slope: must be a number other than 0 within ±") + kRescaleSlopeLimitText);
  return {};
}

Status applyRescale(Volume& volume, IntensityModel& model, double intercept, double slope, IntensityChoice choice) {
  if (auto ok = checkRescale(intercept, slope); !ok) return ok;
  const double newSlope = model.slope * slope, newIntercept = model.intercept * slope + intercept;
  double lowest = std::numeric_limits<double>::infinity();
  for (std::int16_t v : volume.voxels) lowest = std::min(lowest, v * newSlope + newIntercept);
  char given[96];
  std::snprintf(given, sizeof given, "--intercept %g --slope %g", intercept, slope);
  if (choice != IntensityChoice::Plain && (choice == IntensityChoice::Hounsfield || lowest <= -500)) {
    for (std::int16_t& v : volume.voxels)
      v = std::int16_t(std::clamp(std::nearbyint(v * newSlope + newIntercept), -32768.0, 32767.0));
    IntensityModel hu;
    hu.modality = model.modality;
    hu.reason = std::string(given) + (lowest <= -500 ? ": values down to air (<= -500): CT in HU" : ": CT in HU as asked");
    model = hu;
    return {};
  }
  model.slope = newSlope;
  model.intercept = newIntercept;
  model.reason += std::string("; ") + given;
  return {};
}

std::pair<IntensityUnit, std::string> decideIntensity(const IntensityEvidence& e, IntensityChoice choice) {
  if (choice == IntensityChoice::Hounsfield) return {IntensityUnit::Hounsfield, "HU as asked (--intensity hu)"};
  if (choice == IntensityChoice::Plain) return {IntensityUnit::Plain, "plain intensities as asked (--intensity plain)"};
  const bool airInHu = e.minValue <= -500;
  if (e.modality == "CT") {
    if (airInHu) return {IntensityUnit::Hounsfield, "Modality CT, values down to air"};
    return {IntensityUnit::Plain, "Modality CT but no value at or below -500 (air is -1000 HU): CT numbers not in HU"};
  }
  if (!e.modality.empty()) return {IntensityUnit::Plain, "Modality " + e.modality + ": plain intensities"};
  if (e.unsignedStorage && !e.rescaleGiven)
    return {IntensityUnit::Plain, "unsigned integer data without rescale (µCT or MR export): plain intensities"};
  if (airInHu) return {IntensityUnit::Hounsfield, "values down to air (<= -500): CT in HU"};
  return {IntensityUnit::Plain, "no value at or below -500 (no air in HU): plain intensities"};
}

std::array<float, 2> histogramWindow(const std::vector<std::int16_t>& stored) {
  if (stored.empty()) return {0, 1};
  std::vector<std::size_t> counts(65536, 0);
  for (std::int16_t v : stored) ++counts[std::size_t(v + 32768)];
  const auto percentile = [&](double q) {
    const std::size_t wanted = std::size_t(q * double(stored.size() - 1));
    std::size_t seen = 0;
    for (std::size_t b = 0; b < counts.size(); ++b) {
      seen += counts[b];
      if (seen > wanted) return float(int(b) - 32768);
    }
    return 32767.0f;
  };
  float lo = percentile(0.005), hi = percentile(0.995);
  if (!(hi > lo)) hi = lo + 1;
  return {lo, hi};
}

bool looksLikeLabelMap(const FloatVolume& image) {
  std::vector<char> seen(65536, 0);
  std::size_t distinct = 0;
  for (float v : image.voxels) {
    if (!(v >= 0) || v > 65535 || v != std::floor(v)) return false;
    char& s = seen[std::size_t(v)];
    distinct += s == 0;
    s = 1;
  }
  if (distinct > 512) return false;
  const Dims d = image.dims();
  std::size_t pairs = 0, equal = 0;
  const std::size_t step[3] = {1, std::size_t(d.x), std::size_t(d.x) * d.y};
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const std::size_t n = d.index(i, j, k);
        const bool next[3] = {i + 1 < d.x, j + 1 < d.y, k + 1 < d.z};
        for (int a = 0; a < 3; ++a) {
          if (!next[a]) continue;
          const float u = image.voxels[n], v = image.voxels[n + step[a]];
          if (u == 0 || v == 0) continue;
          ++pairs;
          equal += u == v;
        }
      }
  return pairs == 0 || double(equal) >= 0.9 * double(pairs);
}

}  // namespace at
