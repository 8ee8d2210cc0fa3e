// Whether a label map fits the body in its CT: a label map placed wrongly (a header that shifts it
// by tens of slices, a flipped axis) puts most labelled voxels on the air around the patient.
#pragma once

#include <cstddef>
#include <string>

#include "volume/grid.h"
#include "volume/intensity.h"

namespace at {

struct LabelFit {
  std::size_t labelled = 0;     // non-zero label voxels
  std::size_t outsideBody = 0;  // of them, outside the body
  double outsideFraction() const { return labelled ? double(outsideBody) / double(labelled) : 0.0; }
};

// The body: voxels at or above `bodyStored` (a stored value), and voxels enclosed by such voxels
// within their k-slice both along i (on the left and on the right) and along j, so lungs, airways
// and bowel gas count as inside. `labels` lies on `volume`'s grid (same dims).
LabelFit measureLabelFit(const Volume& volume, const LabelMap& labels, double bodyStored);

// One warning line naming `labelsPath` when the labels are on a CT (HU) and more than
// `maxOutside` of at least 1000 labelled voxels lie outside the body (air below −500 HU, not
// enclosed); empty otherwise, and always empty for plain intensities (no air level is known).
std::string labelFitWarning(const Volume& volume, const IntensityModel& intensity, const LabelMap& labels,
                            const std::string& labelsPath, double maxOutside = 0.3);

}  // namespace at
