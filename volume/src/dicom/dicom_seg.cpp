// DICOM SEG (binary Segmentation Storage) through DCMTK's dcmseg → a label map on the SEG's own
// frame geometry. Patient, study and content-creator attributes are never read.
#include "volume/dicom_seg.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include <dcmtk/config/osconfig.h>
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcmetinf.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <dcmtk/dcmdata/dcxfer.h>
#include <dcmtk/dcmfg/fginterface.h>
#include <dcmtk/dcmfg/fgpixmsr.h>
#include <dcmtk/dcmfg/fgplanor.h>
#include <dcmtk/dcmfg/fgplanpo.h>
#include <dcmtk/dcmfg/fgseg.h>
#include <dcmtk/dcmiod/cielabutil.h>
#include <dcmtk/dcmseg/segdoc.h>
#include <dcmtk/dcmseg/segment.h>

#include "../io/load_limits.h"
#include "core/printable_text.h"
#include "core/regular_file.h"
#include "dicom_support.h"
#include "volume/dicom_series.h"

namespace at {

namespace {

using dicom::formatNumber;

// Display colours in DICOM are CIELab; structures carry linear RGB.
std::array<float, 3> linearRgbFromDicomLab(Uint16 l, Uint16 a, Uint16 b) {
  double r = 1, g = 1, bl = 1;
  IODCIELabUtil::dicomLab2RGB(r, g, bl, l, a, b);
  auto linear = [](double c) {
    c = std::clamp(c, 0.0, 1.0);
    return float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
  };
  return {linear(r), linear(g), linear(bl)};
}

// DCMTK 3.6.7's DcmSegmentation::loadFile/loadDataset leak the segmentation they allocate when
// reading it fails: on failure they delete the caller's still-null pointer instead of their own
// object (docs/fuzzing.md has the reproducer). This subclass reaches the protected constructor and
// read(), so the object is owned here from the start and freed on every path.
class OwnedSegmentation : public DcmSegmentation {
 public:
  OwnedSegmentation() = default;
  OFCondition readFrom(DcmItem& dataset) { return read(dataset); }
};

// What loadDataset does before reading: SEG pixel data must be native; RLE (lossless) is decoded,
// other encapsulated syntaxes (possibly lossy) are refused.
Status decompressSegmentation(DcmDataset& dataset) {
  const DcmXfer xfer(dataset.getOriginalXfer());
  if (!xfer.isEncapsulated() || dataset.hasRepresentation(EXS_LittleEndianExplicit, nullptr)) return {};
  if (xfer.getXfer() != EXS_RLELossless)
    return fail(std::string("transfer syntax ") + xfer.getXferName() + " is not supported for segmentations (possibly lossy)");
  if (dataset.chooseRepresentation(EXS_LittleEndianExplicit, nullptr).bad())
    return fail("the RLE-compressed frames cannot be decoded");
  return {};
}

}  // namespace

bool isDicomSegFile(const std::string& path) {
  if (!looksLikeDicomFile(path)) return false;
  dicom::ensureDcmtkReady();
  DcmFileFormat file;
  if (file.loadFile(OFFilename(path.c_str()), EXS_Unknown, EGL_noChange, 256).bad()) return false;
  OFString sopClass;
  file.getDataset()->findAndGetOFString(DCM_SOPClassUID, sopClass);
  if (sopClass.empty()) file.getMetaInfo()->findAndGetOFString(DCM_MediaStorageSOPClassUID, sopClass);
  return sopClass == UID_SegmentationStorage;
}

namespace {

Result<LoadedImage> readDicomSeg(const std::string& path, const ImageLoadOptions& options) {
  dicom::ensureDcmtkReady();
  auto error = [&](const std::string& problem) { return fail(path + ": " + problem); };
  if (auto regular = checkRegularFile(path, path); !regular) return tl::unexpected(regular.error());
  if (!looksLikeDicomFile(path)) return error("not a DICOM file (no DICM preamble)");
  if (!isDicomSegFile(path)) return error("not a DICOM Segmentation Storage object");

  DcmFileFormat file;
  if (const OFCondition loaded = file.loadFile(OFFilename(path.c_str())); loaded.bad())
    return error(std::string("cannot read the segmentation (") + loaded.text() + ")");
  if (auto ok = decompressSegmentation(*file.getDataset()); !ok) return error(ok.error().message);
  auto seg = std::make_unique<OwnedSegmentation>();
  if (const OFCondition read = seg->readFrom(*file.getDataset()); read.bad())
    return error(std::string("cannot read the segmentation (") + read.text() + ")");
  if (seg->getSegmentationType() != DcmSegTypes::ST_BINARY)
    return error("only BINARY segmentations are supported (this one is FRACTIONAL)");

  Uint16 rows = 0, columns = 0;
  // getImagePixel() is public on the image base class (DcmSegmentation narrows it to protected).
  auto& image = static_cast<DcmIODImage<IODImagePixelModule<Uint8>>&>(*seg);
  image.getImagePixel().getRows(rows);
  image.getImagePixel().getColumns(columns);
  const std::size_t frameCount = seg->getNumberOfFrames();
  if (rows == 0 || columns == 0) return error("missing Rows/Columns");
  if (frameCount == 0) return error("the segmentation holds no frames");
  // The frames' bits are read from the dataset's PixelData here, not through dcmseg's getFrame():
  // DCMTK 3.6.7 indexes its frame list out of bounds when NumberOfFrames disagrees with the
  // functional groups (an empty list is read at address 0).
  Uint16 bitsAllocated = 0;
  if (file.getDataset()->findAndGetUint16(DCM_BitsAllocated, bitsAllocated).bad() || bitsAllocated != 1)
    return error("a BINARY segmentation needs BitsAllocated 1, this one has " + std::to_string(bitsAllocated));
  Sint32 declaredFrames = 0;
  if (file.getDataset()->findAndGetSint32(DCM_NumberOfFrames, declaredFrames).bad() || declaredFrames <= 0)
    return error("missing or non-positive NumberOfFrames");
  if (std::size_t(declaredFrames) != frameCount)
    return error("NumberOfFrames is " + std::to_string(declaredFrames) + " but the functional groups describe " +
                 std::to_string(frameCount) + " frames");
  const Uint8* packedBits = nullptr;
  unsigned long packedBytes = 0;
  if (file.getDataset()->findAndGetUint8Array(DCM_PixelData, packedBits, &packedBytes).bad() || !packedBits)
    return error("unreadable PixelData");
  const std::size_t framePixels = std::size_t(rows) * std::size_t(columns);
  if (std::size_t(packedBytes) < (frameCount * framePixels + 7) / 8)
    return error("PixelData holds " + std::to_string(packedBytes) + " bytes, too few for " +
                 std::to_string(frameCount) + " frames of " + std::to_string(columns) + "x" + std::to_string(rows) +
                 " bits (file truncated?)");

  // Per-frame geometry and segment numbers from the functional groups (shared or per frame).
  FGInterface& groups = seg->getFunctionalGroups();
  std::vector<Uint16> segmentOf(frameCount, 0);
  dicom::StackInput stackInput;
  stackInput.allowRepeatsAndGaps = true;
  std::array<double, 6> orientation{};
  double pixelSpacing[2] = {0, 0};
  for (std::size_t f = 0; f < frameCount; ++f) {
    const std::string frameName = "frame " + std::to_string(f + 1);
    auto* position = dynamic_cast<FGPlanePosPatient*>(groups.get(Uint32(f), DcmFGTypes::EFG_PLANEPOSPATIENT));
    auto* plane = dynamic_cast<FGPlaneOrientationPatient*>(groups.get(Uint32(f), DcmFGTypes::EFG_PLANEORIENTPATIENT));
    auto* measures = dynamic_cast<FGPixelMeasures*>(groups.get(Uint32(f), DcmFGTypes::EFG_PIXELMEASURES));
    auto* segment = dynamic_cast<FGSegmentation*>(groups.get(Uint32(f), DcmFGTypes::EFG_SEGMENTATION));
    if (!position || !plane || !measures || !segment)
      return error(frameName + " lacks " +
                   (!position ? "PlanePositionSequence"
                    : !plane  ? "PlaneOrientationSequence"
                    : !measures ? "PixelMeasuresSequence"
                                : "SegmentIdentificationSequence"));
    Float64 x = 0, y = 0, z = 0;
    if (position->getImagePositionPatient(x, y, z).bad()) return error(frameName + ": unreadable ImagePositionPatient");
    std::array<double, 6> o{};
    if (plane->getImageOrientationPatient(o[0], o[1], o[2], o[3], o[4], o[5]).bad())
      return error(frameName + ": unreadable ImageOrientationPatient");
    Float64 rowSpacing = 0, columnSpacing = 0;
    if (measures->getPixelSpacing(rowSpacing, 0).bad() || measures->getPixelSpacing(columnSpacing, 1).bad() ||
        !(rowSpacing > 0) || !(columnSpacing > 0))
      return error(frameName + ": missing or non-positive PixelSpacing");
    if (segment->getReferencedSegmentNumber(segmentOf[f]).bad() || segmentOf[f] == 0)
      return error(frameName + ": missing ReferencedSegmentNumber");
    if (f == 0) {
      orientation = o;
      pixelSpacing[0] = rowSpacing;
      pixelSpacing[1] = columnSpacing;
      Float64 between = 0, thickness = 0;
      if (measures->getSpacingBetweenSlices(between).good() && between > 0)
        stackInput.nominalSpacingMm = between;
      else if (measures->getSliceThickness(thickness).good() && thickness > 0)
        stackInput.nominalSpacingMm = thickness;
    } else {
      for (int i = 0; i < 6; ++i)
        if (std::abs(o[i] - orientation[i]) > 1e-3) return error(frameName + " has a different orientation than frame 1");
      if (std::abs(rowSpacing - pixelSpacing[0]) > 1e-4 * pixelSpacing[0] ||
          std::abs(columnSpacing - pixelSpacing[1]) > 1e-4 * pixelSpacing[1])
        return error(frameName + " has a different PixelSpacing than frame 1");
    }
    stackInput.positionsMm.push_back({x, y, z});
    stackInput.names.push_back(frameName);
  }
  const Vec3 row{orientation[0], orientation[1], orientation[2]};
  const Vec3 column{orientation[3], orientation[4], orientation[5]};
  if (auto ok = dicom::checkOrientation(row, column); !ok) return error(ok.error().message);
  stackInput.row = (1.0 / norm(row)) * row;
  stackInput.column = (1.0 / norm(column)) * column;
  auto stack = dicom::stackSlices(stackInput);
  if (!stack) return error(stack.error().message);

  // Segments: numbers, labels, colours.
  LoadedImage loaded;
  loaded.storedKind = ScalarKind::UInt8;
  std::map<Uint16, std::size_t> segmentIndex;
  const std::size_t segmentCount = seg->getNumberOfSegments();
  for (std::size_t s = 1; s <= segmentCount; ++s) {
    DcmSegment* segment = seg->getSegment(s);
    if (!segment) continue;
    SegmentInfo info;
    info.label = Uint16(s);
    OFString label;
    segment->getSegmentLabel(label);
    info.name = label.empty() ? "segment " + std::to_string(s) : std::string(label.c_str());
    Uint16 l = 0, a = 0, b = 0;
    if (segment->getRecommendedDisplayCIELabValue(l, a, b).good()) info.colour = linearRgbFromDicomLab(l, a, b);
    segmentIndex[info.label] = loaded.segments.size();
    loaded.segments.push_back(info);
  }
  if (segmentCount > 65535) return error("more than 65535 segments");

  Geometry geometry;
  geometry.dims = {int(columns), int(rows), stack->sliceCount};
  geometry.spacingMm = {pixelSpacing[1], pixelSpacing[0], stack->spacingMm};
  geometry.originMm = stack->originMm;
  for (int r = 0; r < 3; ++r) {
    geometry.direction.m[r][0] = stackInput.row[r];
    geometry.direction.m[r][1] = stackInput.column[r];
    geometry.direction.m[r][2] = stack->normal[r];
  }
  // Frames far apart along the normal span many empty slices: check before allocating them.
  if (auto fits = detail::checkImageFits(path, geometry.dims, 0, options); !fits)
    return tl::unexpected(fits.error());
  loaded.image = FloatVolume(geometry, 0.0f);

  // Binary frames are bit-packed and concatenated without padding (PS3.5 8.1.1): pixel p of frame
  // f is bit b % 8 (least significant first) of byte b / 8, where b = f · Rows · Columns + p.
  std::size_t overlapping = 0;
  for (std::size_t f = 0; f < frameCount; ++f) {
    if (!segmentIndex.count(segmentOf[f]))
      return error("frame " + std::to_string(f + 1) + " refers to segment " + std::to_string(segmentOf[f]) +
                   ", which the SegmentSequence does not define");
    float* slice = loaded.image.voxels.data() + std::size_t(stack->sliceOf[f]) * framePixels;
    const float value = float(segmentOf[f]);
    const std::size_t firstBit = f * framePixels;
    for (std::size_t p = 0; p < framePixels; ++p) {
      const std::size_t bit = firstBit + p;
      if (!((packedBits[bit >> 3] >> (bit & 7)) & 1u)) continue;
      if (slice[p] != 0 && slice[p] != value) ++overlapping;
      slice[p] = std::max(slice[p], value);
    }
  }
  auto counted = [](std::size_t n, const char* what) { return std::to_string(n) + " " + what + (n == 1 ? "" : "s"); };
  loaded.notes.push_back("DICOM SEG: " + counted(loaded.segments.size(), "segment") + " in " +
                         counted(frameCount, "frame") + " on " + geometry.dims.toString() + " voxels");
  if (overlapping)
    loaded.notes.push_back("segments overlap (" + std::to_string(overlapping) +
                           " voxel claims by a second segment); the higher segment number wins");
  return loaded;
}

}  // namespace

Result<LoadedImage> loadDicomSeg(const std::string& path, const ImageLoadOptions& options) {
  return withPrintableError(readDicomSeg(path, options));
}

}  // namespace at
