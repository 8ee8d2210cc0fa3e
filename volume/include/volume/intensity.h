// What a dataset's voxel values mean (ARCHITECTURE.md §2): CT in Hounsfield units, or plain
// intensities (µCT exports, MR, anything else) that only order materials from dark to bright.
// Voxels are stored as int16 (Volume); the model maps a stored value to the file's value and says
// which window of stored values is "density 0 … 1" for the WDT's density weights and is the
// default grey window of slices.
//
// How a loaded image gets its model (decideIntensity, documented there) and how `info` tells a
// label map from an image (looksLikeLabelMap) are written here once for every command.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"

namespace at {

enum class IntensityUnit { Hounsfield, Plain };

struct IntensityModel {
  IntensityUnit unit = IntensityUnit::Hounsfield;
  // DICOM Modality ("CT", "MR", …) where the file says or the user gave it (--modality); else empty
  std::string modality;
  // value = stored · slope + intercept: HU, or the file's intensity (uint16 data above 32767 and
  // fractional data are stored shifted and scaled to fit int16).
  double slope = 1, intercept = 0;
  // Stored values mapped to density 0 and 1 (WDT density weights, grow-from-seeds costs) and shown
  // as the default grey window: −1000 … 2000 HU for CT, percentiles of the histogram otherwise.
  std::array<float, 2> window{-1000, 2000};
  std::string reason;  // one line: how the unit was decided ("DICOM Modality CT", "unsigned uint8 data", …)

  bool hounsfield() const { return unit == IntensityUnit::Hounsfield; }
  // Whether brighter means denser: a volume with no modality (µCT exports, NIfTI/NRRD CT), an X-ray
  // modality (CT, DX, CR, MG, XA, RF, …) or "OT" (other: unknown). Any other modality (MR, PT, NM,
  // US, …) measures something that is not attenuation: density-weighted distances on it assume a
  // CT-like meaning the data does not have (isAttenuationModality).
  bool attenuationLike() const;
  double valueOf(double stored) const { return stored * slope + intercept; }
  const char* unitName() const { return hounsfield() ? "HU" : "intensity"; }
};

// Whether a DICOM Modality code names attenuation imaging (see attenuationLike): empty, "OT", or
// one of the X-ray modalities.
bool isAttenuationModality(const std::string& modality);

// A modality the user gives for a file that records none (--modality, the import window): a DICOM
// code, case-insensitive ("mr" is MR). Errors name the field: "modality: 'x' is not …".
Result<std::string> parseModalityCode(const std::string& text);

// What the user asked for: decide from the file (auto), or force one unit.
enum class IntensityChoice { Auto, Hounsfield, Plain };
Result<IntensityChoice> parseIntensityChoice(const std::string& text);  // "auto" | "hu" | "plain"

// What the loader knows about an image's values, the input of decideIntensity.
struct IntensityEvidence {
  std::string modality;       // DICOM Modality: the file's, or one given for a file without; else empty
  bool rescaleGiven = false;  // DICOM RescaleSlope/Intercept present, or NIfTI scl_slope set
  bool unsignedStorage = false;  // stored as uint8/uint16/uint32
  double minValue = 0, maxValue = 0;  // after any rescale
};

// The unit of an image, in this order:
//   1. a forced choice (--intensity hu|plain);
//   2. DICOM Modality CT: HU if some value is at or below −500 (air is −1000 HU); CT numbers never
//      rescaled to HU (air at 0, as in VTK's headsq) are plain; any other modality: plain;
//   3. no modality (NIfTI, NRRD): unsigned storage without rescale is plain (µCT exports, MR);
//      otherwise HU if some value is at or below −500 (air is −1000 HU), plain if none is.
// Returns the unit and the reason line.
std::pair<IntensityUnit, std::string> decideIntensity(const IntensityEvidence& evidence, IntensityChoice choice);

// A rescale the user gives where the file calibrates nothing (a raw or NRRD volume, a CT stored
// without its rescale): values v become v·slope + intercept (after the file's own mapping). Where
// the result reaches air (≤ −500) or `choice` is Hounsfield, and `choice` is not Plain, the volume
// becomes CT in HU: its voxels are stored as HU and its model is the HU model. Otherwise the model
// keeps plain intensities with the rescale in its value mapping. The reason line names the options
// ("--intercept -1024 --slope 1"). Errors: a slope of 0 or a value that is not finite.
Status applyRescale(Volume& volume, IntensityModel& model, double intercept, double slope, IntensityChoice choice);
// The rule applyRescale checks first, for callers that refuse a bad rescale before loading (an
// import): an intercept within ±1e15, a slope other than 0 within ±1e12 (so that every int16 value
// maps to a finite one); the message names the option.
inline constexpr double kRescaleInterceptLimit = 1e15, kRescaleSlopeLimit = 1e12;
inline constexpr const char* kRescaleInterceptLimitText = "1e15";
inline constexpr const char* kRescaleSlopeLimitText = "1e12";
Status checkRescale(double intercept, double slope);
// The inverse of parseIntensityChoice ("auto", "hu", "plain").
const char* intensityChoiceName(IntensityChoice choice);

// The window of plain intensities: the 0.5th and 99.5th percentiles of the stored values, widened
// to at least one step. (A µCT's air then sits at density ≈ 0 and its densest bone at ≈ 1.)
std::array<float, 2> histogramWindow(const std::vector<std::int16_t>& stored);

// Whether an integer image is a label map rather than an intensity image (used by `info`, which has
// no --labels to go by): all values integers 0 … 65535, at most 512 distinct ones, and
// piecewise constant — of the face-adjacent pairs of non-zero voxels, at least 90 % hold equal
// values (TotalSegmentator's 41 labels at 3 mm: 99.4 %). A µCT (uint8 or uint16) fails the last
// test: its neighbouring voxels differ by noise and texture; a label map's only on structure
// borders.
bool looksLikeLabelMap(const FloatVolume& image);

}  // namespace at
