// Internal helpers shared by the DICOM loaders (series, SEG, file dispatch). Not a public header, and
// it includes no DCMTK header, so DCMTK's slow headers stay inside the loaders' own .cpp files.
#pragma once

#include <string>
#include <vector>

#include "core/error.h"
#include "volume/geometry.h"

namespace at::dicom {

// Registers DCMTK's decoders (JPEG, JPEG-LS, RLE) once per process and lowers DCMTK's own logging
// to fatal errors (its warnings would otherwise go to stderr; our errors travel as values).
// Thread-safe; the codecs are released at process exit.
void ensureDcmtkReady();

// SeriesInstanceUID of one DICOM file (empty if the file has none).
Result<std::string> readSeriesInstanceUid(const std::string& path);

// "2", "2.5", "0.977": a number for messages, at most three decimals, no trailing zeros.
std::string formatNumber(double value);

// Checks ImageOrientationPatient's row and column cosines: unit length and orthogonal within 1e-3
// (DS rounding stays well inside that). The error names the problem.
Status checkOrientation(const Vec3& row, const Vec3& column);

// Placing 2-D slices (series files or SEG frames) into one 3-D grid along the slice normal.
struct StackInput {
  std::vector<Vec3> positionsMm;   // ImagePositionPatient of each slice, LPS
  std::vector<std::string> names;  // per slice, for messages: "CT3.dcm", "frame 4"
  Vec3 row{1, 0, 0}, column{0, 1, 0};  // unit cosines (checked by checkOrientation)
  // SEG: several frames may share a position (one per segment) and positions without any
  // segment are left out of the file, so repeats and whole-slice gaps are allowed.
  bool allowRepeatsAndGaps = false;
  // Used when it fits the positions (SEG's SpacingBetweenSlices), and for a single slice.
  double nominalSpacingMm = 0;
};

struct SliceStack {
  std::vector<int> sliceOf;  // k index of each input slice
  int sliceCount = 0;
  double spacingMm = 1;      // between slices along the normal
  Vec3 originMm{0, 0, 0};    // position of slice k = 0
  Vec3 normal{0, 0, 1};      // unit row × column: direction of increasing k
};

// Sorts by position along the normal and derives the spacing from the positions. Errors (one line,
// no path prefix: the caller adds it): slices at the same position, gantry tilt (positions not
// advancing along the normal), missing slices (a gap of a multiple of the spacing), uneven spacing
// (the distinct spacings listed).
Result<SliceStack> stackSlices(const StackInput& input);

}  // namespace at::dicom
