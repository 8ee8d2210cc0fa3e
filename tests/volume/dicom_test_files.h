// Test helpers that make DICOM inputs with DCMTK: copies of the real files in ../shared/data with
// some attributes changed (broken series, marker identifiers, shifted segmentations).
#pragma once

#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>

#include <dcmtk/config/osconfig.h>
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcitem.h>
#include <dcmtk/dcmdata/dcsequen.h>

namespace at::test {

// Loads `from`, lets `edit` change the dataset, saves to `to` in the original transfer syntax.
// Returns false (and the test should fail) if DCMTK cannot read or write.
inline bool rewriteDicom(const std::filesystem::path& from, const std::filesystem::path& to,
                         const std::function<void(DcmDataset&)>& edit) {
  DcmFileFormat file;
  if (file.loadFile(OFFilename(from.c_str())).bad()) return false;
  if (!file.getDataset()->loadAllDataIntoMemory().good()) return false;
  edit(*file.getDataset());
  return file.saveFile(OFFilename(to.c_str()), EXS_Unknown).good();
}

inline std::string dicomString(const std::filesystem::path& path, const DcmTagKey& tag) {
  DcmFileFormat file;
  OFString value;
  if (file.loadFile(OFFilename(path.c_str())).good()) file.getDataset()->findAndGetOFString(tag, value, 0, OFTrue);
  return value.c_str();
}

// The transfer syntax a file's data set is encoded in.
inline E_TransferSyntax dicomTransferSyntax(const std::filesystem::path& path) {
  DcmFileFormat file;
  if (file.loadFile(OFFilename(path.c_str())).bad()) return EXS_Unknown;
  return file.getDataset()->getOriginalXfer();
}

// A DS/FD/IS attribute's value `index` of a file (NaN when absent).
inline double dicomNumber(const std::filesystem::path& path, const DcmTagKey& tag, unsigned long index = 0) {
  DcmFileFormat file;
  Float64 value = 0;
  if (file.loadFile(OFFilename(path.c_str())).bad()) return std::nan("");
  if (file.getDataset()->findAndGetFloat64(tag, value, index).good()) return value;
  Uint16 u = 0;
  if (file.getDataset()->findAndGetUint16(tag, u, index).good()) return u;
  return std::nan("");
}

inline void setPosition(DcmDataset& data, const std::array<double, 3>& p) {
  const std::string value = std::to_string(p[0]) + "\\" + std::to_string(p[1]) + "\\" + std::to_string(p[2]);
  data.putAndInsertString(DCM_ImagePositionPatient, value.c_str());
}

inline std::array<double, 3> positionOf(DcmDataset& data) {
  std::array<double, 3> p{0, 0, 0};
  for (unsigned long i = 0; i < 3; ++i) data.findAndGetFloat64(DCM_ImagePositionPatient, p[i], i);
  return p;
}

// Applies `edit` to the ImagePositionPatient of every frame of a multi-frame object (DICOM SEG).
inline void editFramePositions(DcmDataset& data, const std::function<std::array<double, 3>(std::array<double, 3>)>& edit) {
  DcmSequenceOfItems* frames = nullptr;
  if (data.findAndGetSequence(DCM_PerFrameFunctionalGroupsSequence, frames).bad() || !frames) return;
  for (unsigned long f = 0; f < frames->card(); ++f) {
    DcmItem* planeItem = nullptr;
    if (frames->getItem(f)->findAndGetSequenceItem(DCM_PlanePositionSequence, planeItem).bad() || !planeItem) continue;
    std::array<double, 3> p{0, 0, 0};
    for (unsigned long i = 0; i < 3; ++i) planeItem->findAndGetFloat64(DCM_ImagePositionPatient, p[i], i);
    p = edit(p);
    const std::string value = std::to_string(p[0]) + "\\" + std::to_string(p[1]) + "\\" + std::to_string(p[2]);
    planeItem->putAndInsertString(DCM_ImagePositionPatient, value.c_str());
  }
}

}  // namespace at::test
