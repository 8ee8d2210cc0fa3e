// Writing a label map with its structures, in forms the app and other tools read back:
//   - a NIfTI uint16 label map (writeNiftiLabels, nifti_io.h) with a names JSON
//     { "1": "liver", … } — what `--labels FILE --names NAMES.json` and `import` take;
//   - a 3D Slicer segmentation (.seg.nrrd): one layer of label values with Segment<N>_ID, _Name,
//     _Color, _LabelValue, _Layer and _Extent keys — Slicer's Segment Editor opens it, and loadNrrd
//     reads it back (names, colours, values).
#pragma once

#include <string>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"
#include "volume/structure.h"

namespace at {

// { "label value": "name", … } for the structures (display names), pretty-printed.
Status writeLabelNames(const std::string& path, const std::vector<Structure>& structures);

// The label map as a .seg.nrrd (uint8 when every label is below 256, else uint16). Voxels whose
// label no structure names are written as they are, without a segment. Errors name the file.
Status writeSegNrrd(const std::string& path, const LabelMap& labels, const std::vector<Structure>& structures);

}  // namespace at
