// Which way a slice picture shows the patient: the one rule that maps screen directions to patient
// directions, shared by the desktop's slice panes and the CLI `slice --plane`.
//
// Radiological convention (as on a radiology workstation): axial panes are seen from the feet and
// coronal panes from the front, so the patient's LEFT is on the screen's RIGHT; sagittal panes are
// seen from the patient's left, anterior on the screen's left. Superior is up (coronal, sagittal)
// and anterior is up (axial). The layout follows from the grid's direction cosines, so a NIfTI
// (RAS, rows and slices stored the other way) and its DICOM series show the same picture.
#pragma once

#include <array>
#include <string>

#include "volume/geometry.h"

namespace at {

enum class PatientPlane { Sagittal = 0, Coronal = 1, Axial = 2 };

const char* planeName(PatientPlane plane);  // "sagittal", "coronal", "axial"

// How a slice picture is laid out over voxel axes. Column c of the picture is voxel
// (columnReversed ? n − 1 − c : c) along columnAxis, likewise rows (row 0 at the top).
struct SliceLayout {
  int sliceAxis = 2;            // voxel axis the picture is perpendicular to
  int columnAxis = 0;           // voxel axis along the picture's columns (left → right)
  bool columnReversed = false;
  int rowAxis = 1;              // voxel axis along the picture's rows (top → bottom)
  bool rowReversed = false;
  // Patient direction letters (L R A P S I) at the picture's left, right, top and bottom edges.
  char left = '?', right = '?', top = '?', bottom = '?';

  std::string edgeLetters() const;  // e.g. "left R, right L, top A, bottom P"
};

// The layout of `plane` for a grid with these direction cosines (columns: unit i, j, k in LPS) in
// the radiological convention above. Each voxel axis is matched to the patient axis it points
// along most (for oblique grids: the assignment with the largest total alignment), so the picture
// is the nearest unrotated patient view.
SliceLayout patientSliceLayout(const Mat3& direction, PatientPlane plane);

// Raw voxel order across voxel axis 0, 1 or 2 (columns i, or j for axis 0; rows j for axis 2, else k
// from the highest down) with letters from `direction`; what `slice --axis` has always drawn.
SliceLayout voxelSliceLayout(int axis, const Mat3& direction = Mat3::identity());

}  // namespace at
