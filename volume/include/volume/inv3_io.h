// InVesalius 3 projects (.inv3): a tar archive, gzip-compressed or not, holding a folder with
// `main.plist` (an XML property list: the image's shape, numpy dtype and spacing) and the raw
// voxel matrix it names (`matrix.dat`: C order z,y,x, little endian). Masks, surfaces and
// measurements in the same archive are not read.
//
// InVesalius keeps no patient position, so the grid is placed in its own axis convention with the
// origin at voxel (0,0,0): x (i) toward the patient's left (it keeps the DICOM columns), y (j)
// toward anterior (it flips the DICOM rows), z (k) toward superior; in this project's LPS terms the
// direction is diag(1, -1, 1), orientation code "LAS". The patient name stored in main.plist is
// never copied out.
#pragma once

#include <string>

#include "core/error.h"
#include "volume/image_file.h"

namespace at {

// Errors name the file and the problem in one line: not an archive, a damaged or truncated
// archive, no main.plist, a plist that is not a property list or lacks a field, an unsupported
// dtype, no matrix member, a matrix whose byte count does not match shape × dtype.
Result<LoadedImage> loadInv3(const std::string& path, const ImageLoadOptions& options = {});

}  // namespace at
