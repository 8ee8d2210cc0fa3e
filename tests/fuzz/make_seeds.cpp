// at_fuzz_seeds OUT_DIR: writes the seed corpus of every harness into OUT_DIR/<harness>/ — small
// valid files of each kind (written with the project's own writers, DCMTK and OpenJPEG, so that
// no binary seed needs committing), the repository's JSON data, and the small real files of
// ../shared/data when it exists. Hand-made seeds and past findings live in tests/fuzz/corpus/ and
// tests/fuzz/regressions/ and are added by scripts/fuzz.sh.
//
// Sections: [files] · [nifti] · [nrrd] · [seg.nrrd] · [dicom] · [seg] · [png] · [inv3] · [json] ·
// [package] · main

// The loader tests' file writers (io_test_files.h) come with doctest checks this program never
// runs: compiled out, so that no doctest runtime is needed.
#define DOCTEST_CONFIG_DISABLE
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <dcmtk/config/osconfig.h>
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcpixel.h>
#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dcpxitem.h>
#include <dcmtk/dcmdata/dcrleerg.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <dcmtk/dcmfg/fgfracon.h>
#include <dcmtk/dcmfg/fgpixmsr.h>
#include <dcmtk/dcmfg/fgplanor.h>
#include <dcmtk/dcmfg/fgplanpo.h>
#include <dcmtk/dcmjpeg/djencode.h>
#include <dcmtk/dcmjpeg/djrplol.h>
#include <dcmtk/dcmjpls/djencode.h>
#include <dcmtk/dcmjpls/djrparam.h>
#include <dcmtk/dcmseg/segdoc.h>
#include <dcmtk/dcmseg/segment.h>
#include <dcmtk/oflog/oflog.h>
#include <archive.h>
#include <archive_entry.h>
#include <openjpeg.h>
#include <png.h>

#include "inv3_test_files.h"
#include "io_test_files.h"
#include "lessons/course_json.h"
#include "package/course_package.h"
#include "quiz/answer_json.h"
#include "quiz/study_report.h"
#include "study_long_csv_study.h"
#include "render/preset.h"
#include "segment/seeds.h"
#include "volume/dataset_source.h"
#include "volume/label_writers.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"
#include "volume/png_image.h"

namespace fs = std::filesystem;
using namespace at;

namespace {

// ---------------------------------------------------------------------------------------------
// [files]

fs::path outRoot;
int written = 0;

bool failed = false;

// Writes one seed; an empty one means its generator failed (already reported): the run fails.
void seed(const std::string& harness, const std::string& name, const std::string& bytes) {
  if (bytes.empty()) {
    std::fprintf(stderr, "at_fuzz_seeds: no seed %s/%s\n", harness.c_str(), name.c_str());
    failed = true;
    return;
  }
  const fs::path dir = outRoot / harness;
  fs::create_directories(dir);
  std::ofstream out(dir / name, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), std::streamsize(bytes.size()));
  ++written;
}

std::string readAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Several files joined as the multi-file harnesses split them (fuzz_support.h).
std::string joinParts(const std::vector<std::string>& parts) {
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i) out += (i ? "\n--8<--\n" : "") + parts[i];
  return out;
}

fs::path sharedData() {
  const fs::path dir = AT_SHARED_DATA_DIR;
  std::error_code ec;
  return fs::is_directory(dir, ec) ? dir : fs::path();
}

// A small image with a gradient and a few distinct values (so conversions see varied numbers).
FloatVolume smallImage(Dims dims, float scale, float offset) {
  Geometry g;
  g.dims = dims;
  g.spacingMm = {0.8, 0.9, 2.5};
  g.originMm = {-10, 20, 5};
  FloatVolume image(g);
  for (std::size_t n = 0; n < image.voxels.size(); ++n) image.voxels[n] = offset + scale * float(n % 7);
  return image;
}

// Writes with a project writer into a temporary file and returns its bytes.
template <class Write>
std::string bytesOfWritten(const std::string& name, Write write) {
  const fs::path path = outRoot / (".tmp-" + name);
  auto ok = write(path.string());
  std::string bytes = ok ? readAll(path) : std::string();
  std::error_code ec;
  fs::remove(path, ec);
  if (!ok) std::fprintf(stderr, "at_fuzz_seeds: %s\n", ok.error().message.c_str());
  return bytes;
}

// ---------------------------------------------------------------------------------------------
// [nifti]

void niftiSeeds() {
  const FloatVolume hu = smallImage({4, 3, 2}, 100, -1000);
  seed("nifti", "float_v1.nii", bytesOfWritten("a.nii", [&](const std::string& p) { return writeNiftiFloat(p, hu); }));
  seed("nifti", "float_v1.nii.gz",
       bytesOfWritten("a.nii.gz", [&](const std::string& p) { return writeNiftiFloat(p, hu); }));
  LabelMap labels(hu.geometry, 0);
  for (std::size_t n = 0; n < labels.voxels.size(); ++n) labels.voxels[n] = std::uint16_t(n % 3);
  seed("nifti", "labels_u16.nii.gz",
       bytesOfWritten("b.nii.gz", [&](const std::string& p) { return writeNiftiLabels(p, labels); }));

  test::RawNifti raw;
  raw.dims[0] = 3, raw.dims[1] = 2, raw.dims[2] = 2;
  raw.sformCode = 1;
  raw.srow[0][0] = -0.7, raw.srow[1][1] = -0.7, raw.srow[2][2] = 3;
  raw.data.assign(3 * 2 * 2 * 2, '\x01');
  seed("nifti", "int16_sform_v1.nii", raw.bytes());
  raw.version = 2;
  raw.sformCode = 0;
  raw.qformCode = 1;
  raw.quatern[2] = 1;  // 180° about z
  seed("nifti", "int16_qform_v2.nii", raw.bytes());
  raw.version = 1;
  raw.qformCode = 0;
  raw.datatype = 2, raw.bitpix = 8;  // uint8, pixdim scaling only
  raw.slope = 2, raw.inter = -5;
  raw.data.assign(3 * 2 * 2, '\x07');
  seed("nifti", "uint8_slope_v1.nii", raw.bytes());
  raw.datatype = 64, raw.bitpix = 64;  // float64
  raw.slope = 0, raw.inter = 0;
  raw.data.assign(3 * 2 * 2 * 8, '\0');
  seed("nifti", "float64_v1.nii", raw.bytes());
  raw.extraDim4 = 1;
  raw.datatype = 8, raw.bitpix = 32;  // int32
  raw.data.assign(3 * 2 * 2 * 4, '\x02');
  seed("nifti", "int32_v1.nii", raw.bytes());
}

// ---------------------------------------------------------------------------------------------
// [nrrd]

std::string rawInt16(std::size_t count, bool bigEndian) {
  std::string data;
  for (std::size_t n = 0; n < count; ++n) {
    const std::int16_t v = std::int16_t(int(n) * 37 - 500);
    const auto u = std::uint16_t(v);
    const char lo = char(u & 0xff), hi = char(u >> 8);
    data += bigEndian ? std::string{hi, lo} : std::string{lo, hi};
  }
  return data;
}

void nrrdSeeds() {
  const FloatVolume hu = smallImage({4, 3, 2}, 100, -1000);
  for (const auto& entry : {std::pair{ScalarKind::Int16, "gzip_short.nrrd"}, std::pair{ScalarKind::UInt8, "gzip_uchar.nrrd"},
                            std::pair{ScalarKind::Float32, "gzip_float.nrrd"}}) {
    const ScalarKind kind = entry.first;
    const char* name = entry.second;
    const FloatVolume image = kind == ScalarKind::UInt8 ? smallImage({4, 3, 2}, 1, 0) : hu;
    seed("nrrd", name, bytesOfWritten(name, [&](const std::string& p) { return writeNrrd(p, image, kind); }));
  }
  const std::string header =
      "NRRD0004\n# Complete NRRD file format specification at:\ntype: short\ndimension: 3\n"
      "space: left-posterior-superior\nsizes: 4 3 2\nspace directions: (0.8,0,0) (0,0.9,0) (0,0,2.5)\n"
      "kinds: domain domain domain\n";
  seed("nrrd", "raw_little.nrrd",
       header + "endian: little\nencoding: raw\nspace origin: (-10,20,5)\n\n" + rawInt16(24, false));
  seed("nrrd", "raw_big_skips.nrrd",
       header + "endian: big\nencoding: raw\nline skip: 1\nbyte skip: 2\n\nskipped line\nXX" + rawInt16(24, true));
  seed("nrrd", "raw_byte_skip_minus1.nrrd",
       header + "endian: little\nencoding: raw\nbyte skip: -1\n\njunk" + rawInt16(24, false));
  seed("nrrd", "slicer_seg.nrrd",
       "NRRD0004\ntype: unsigned char\ndimension: 4\nspace: right-anterior-superior\nsizes: 1 4 3 2\n"
       "space directions: none (1,0,0) (0,1,0) (0,0,2)\nkinds: list domain domain domain\nencoding: raw\n"
       "space origin: (0,0,0)\nSegment0_Name:=liver\nSegment0_LabelValue:=1\nSegment0_Color:=0.8 0.3 0.2\n"
       "Segment1_Name:=spleen\nSegment1_LabelValue:=2\n\n" +
           std::string("\x00\x01\x02\x01\x00\x01\x02\x01\x00\x01\x02\x01\x00\x01\x02\x01\x00\x01\x02\x01\x00\x01\x02\x01",
                       24));
  seed("nrrd", "spacings_double.nrrd",
       "NRRD0005\ntype: double\ndimension: 3\nsizes: 2 2 1\nspacings: 1.5 1.5 3\nendian: little\nencoding: raw\n\n" +
           std::string(32, '\0'));
  if (const fs::path shared = sharedData(); !shared.empty())
    for (const char* name : {"dcmqi/spine_seg_label5.nrrd", "dcmqi/heart_seg.nrrd"})
      seed("nrrd", fs::path(name).filename().string(), readAll(shared / name));

  // Detached headers: part 1 is image.nhdr, the next parts data1.raw, data2.raw, … (and data.raw = data1.raw).
  const std::string detached =
      "NRRD0004\ntype: short\ndimension: 3\nspace: 3D-left-handed\nsizes: 4 3 3\nspacings: 1 1 1.5\n"
      "endian: little\nencoding: raw\n";
  const std::string slice0 = rawInt16(12, false), slice1 = rawInt16(12, false), slice2 = rawInt16(12, false);
  seed("nrrd_detached", "single.nhdr", joinParts({detached + "data file: data.raw\n", slice0 + slice1 + slice2}));
  seed("nrrd_detached", "numbered.nhdr",
       joinParts({detached + "data file: data%d.raw 1 3 1\n", slice0, slice1, slice2}));
  seed("nrrd_detached", "list.nhdr",
       joinParts({detached + "data file: LIST\ndata1.raw\ndata2.raw\ndata3.raw\n", slice0, slice1, slice2}));
  const FloatVolume small = smallImage({4, 3, 1}, 3, 1);
  const std::string gz = bytesOfWritten("g.nrrd", [&](const std::string& p) { return writeNrrd(p, small, ScalarKind::Int16); });
  const std::size_t blank = gz.find("\n\n");
  if (blank != std::string::npos)
    seed("nrrd_detached", "gzip.nhdr",
         joinParts({"NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 1\nendian: little\nencoding: gzip\n"
                    "data file: data.raw\n",
                    gz.substr(blank + 2)}));
}

// ---------------------------------------------------------------------------------------------
// [dicom]

struct SliceSpec {
  int rows = 8, columns = 8;
  double z = 0;
  int bitsAllocated = 16;
  bool signedPixels = true;
  const char* seriesUid = "1.2.826.0.1.3680043.9.7133.1.1";
};

// A CT slice in the native (uncompressed) representation.
DcmFileFormat ctSlice(const SliceSpec& s) {
  DcmFileFormat file;
  DcmDataset& d = *file.getDataset();
  d.putAndInsertString(DCM_SOPClassUID, UID_CTImageStorage);
  char uid[100];
  d.putAndInsertString(DCM_SOPInstanceUID, dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT));
  d.putAndInsertString(DCM_Modality, "CT");
  d.putAndInsertString(DCM_SeriesInstanceUID, s.seriesUid);
  d.putAndInsertUint16(DCM_Rows, Uint16(s.rows));
  d.putAndInsertUint16(DCM_Columns, Uint16(s.columns));
  d.putAndInsertUint16(DCM_SamplesPerPixel, 1);
  d.putAndInsertString(DCM_PhotometricInterpretation, "MONOCHROME2");
  d.putAndInsertUint16(DCM_BitsAllocated, Uint16(s.bitsAllocated));
  d.putAndInsertUint16(DCM_BitsStored, Uint16(s.bitsAllocated == 16 ? 12 : 8));
  d.putAndInsertUint16(DCM_HighBit, Uint16(s.bitsAllocated == 16 ? 11 : 7));
  d.putAndInsertUint16(DCM_PixelRepresentation, s.signedPixels ? 1 : 0);
  d.putAndInsertString(DCM_RescaleSlope, "1");
  d.putAndInsertString(DCM_RescaleIntercept, s.signedPixels ? "0" : "-1024");
  d.putAndInsertString(DCM_PixelSpacing, "0.75\\0.75");
  d.putAndInsertString(DCM_SliceThickness, "2");
  d.putAndInsertString(DCM_ImageOrientationPatient, "1\\0\\0\\0\\1\\0");
  const std::string position = "-3\\-3\\" + std::to_string(s.z);
  d.putAndInsertString(DCM_ImagePositionPatient, position.c_str());
  const std::size_t count = std::size_t(s.rows) * std::size_t(s.columns);
  if (s.bitsAllocated == 16) {
    std::vector<Uint16> pixels(count);
    for (std::size_t i = 0; i < count; ++i) pixels[i] = Uint16((i * 53 + std::size_t(s.z) * 7) % 2048);
    d.putAndInsertUint16Array(DCM_PixelData, pixels.data(), static_cast<unsigned long>(count));
  } else {
    std::vector<Uint8> pixels(count);
    for (std::size_t i = 0; i < count; ++i) pixels[i] = Uint8((i * 13) % 256);
    d.putAndInsertUint8Array(DCM_PixelData, pixels.data(), static_cast<unsigned long>(count));
  }
  return file;
}

std::string saveDicom(DcmFileFormat& file, E_TransferSyntax xfer, const DcmRepresentationParameter* parameters = nullptr) {
  DcmDataset& d = *file.getDataset();
  if (DcmXfer(xfer).isEncapsulated() && d.chooseRepresentation(xfer, parameters).bad()) {
    std::fprintf(stderr, "at_fuzz_seeds: DCMTK cannot encode %s\n", DcmXfer(xfer).getXferName());
    return {};
  }
  const fs::path path = outRoot / ".tmp.dcm";
  if (file.saveFile(OFFilename(path.c_str()), xfer).bad()) {
    std::fprintf(stderr, "at_fuzz_seeds: DCMTK cannot write %s\n", DcmXfer(xfer).getXferName());
    return {};
  }
  std::string bytes = readAll(path);
  fs::remove(path);
  return bytes;
}

// A J2K codestream of the slice's pixels (lossless), through OpenJPEG's encoder.
std::vector<std::uint8_t> encodeJ2k(const std::vector<std::int32_t>& pixels, int width, int height, int precision,
                                    bool isSigned) {
  opj_image_cmptparm_t component{};
  component.dx = component.dy = 1;
  component.w = OPJ_UINT32(width);
  component.h = OPJ_UINT32(height);
  component.prec = OPJ_UINT32(precision);
  component.sgnd = isSigned ? 1 : 0;
  opj_image_t* image = opj_image_create(1, &component, OPJ_CLRSPC_GRAY);
  image->x1 = OPJ_UINT32(width);
  image->y1 = OPJ_UINT32(height);
  std::copy(pixels.begin(), pixels.end(), image->comps[0].data);
  opj_cparameters_t parameters;
  opj_set_default_encoder_parameters(&parameters);
  parameters.tcp_numlayers = 1;
  parameters.tcp_rates[0] = 0;  // lossless
  parameters.cp_disto_alloc = 1;
  parameters.numresolution = 2;
  opj_codec_t* codec = opj_create_compress(OPJ_CODEC_J2K);
  opj_setup_encoder(codec, &parameters, image);
  struct Sink {
    std::vector<std::uint8_t> bytes;
    std::size_t at = 0;
  } sink;
  opj_stream_t* stream = opj_stream_default_create(OPJ_FALSE);
  opj_stream_set_user_data(stream, &sink, nullptr);
  opj_stream_set_write_function(stream, [](void* buffer, OPJ_SIZE_T n, void* user) -> OPJ_SIZE_T {
    auto* s = static_cast<Sink*>(user);
    if (s->bytes.size() < s->at + n) s->bytes.resize(s->at + n);
    std::memcpy(s->bytes.data() + s->at, buffer, n);
    s->at += n;
    return n;
  });
  opj_stream_set_skip_function(stream, [](OPJ_OFF_T n, void* user) -> OPJ_OFF_T {
    static_cast<Sink*>(user)->at += std::size_t(n);
    return n;
  });
  opj_stream_set_seek_function(stream, [](OPJ_OFF_T n, void* user) -> OPJ_BOOL {
    static_cast<Sink*>(user)->at = std::size_t(n);
    return OPJ_TRUE;
  });
  const bool ok = opj_start_compress(codec, image, stream) && opj_encode(codec, stream) && opj_end_compress(codec, stream);
  opj_stream_destroy(stream);
  opj_destroy_codec(codec);
  opj_image_destroy(image);
  if (!ok) sink.bytes.clear();
  return sink.bytes;
}

// A JPEG 2000 lossless slice: the native slice's pixels as one encapsulated J2K fragment.
std::string jpeg2000Slice(const SliceSpec& s) {
  DcmFileFormat file = ctSlice(s);
  DcmDataset& d = *file.getDataset();
  const Uint16* native = nullptr;
  d.findAndGetUint16Array(DCM_PixelData, native);
  const std::size_t count = std::size_t(s.rows) * std::size_t(s.columns);
  std::vector<std::int32_t> pixels(native, native + count);
  const auto j2k = encodeJ2k(pixels, s.columns, s.rows, 12, false);
  if (j2k.empty()) return {};
  auto* sequence = new DcmPixelSequence(DcmTag(DCM_PixelData, EVR_OB));
  sequence->insert(new DcmPixelItem(DcmTag(DCM_Item, EVR_OB)));  // empty basic offset table
  auto* fragment = new DcmPixelItem(DcmTag(DCM_Item, EVR_OB));
  std::vector<std::uint8_t> even = j2k;
  if (even.size() % 2) even.push_back(0);
  fragment->putUint8Array(even.data(), static_cast<unsigned long>(even.size()));
  sequence->insert(fragment);
  DcmPixelData* pixelData = nullptr;
  DcmElement* element = nullptr;
  d.findAndGetElement(DCM_PixelData, element);
  pixelData = dynamic_cast<DcmPixelData*>(element);
  if (!pixelData) return {};
  pixelData->putOriginalRepresentation(EXS_JPEG2000LosslessOnly, nullptr, sequence);
  return saveDicom(file, EXS_JPEG2000LosslessOnly);
}

void dicomSeriesSeeds() {
  DJEncoderRegistration::registerCodecs();
  DJLSEncoderRegistration::registerCodecs();
  DcmRLEEncoderRegistration::registerCodecs();
  const SliceSpec base;
  std::vector<std::string> explicitSlices;
  for (int k = 0; k < 3; ++k) {
    SliceSpec s = base;
    s.z = 2.0 * k;
    DcmFileFormat file = ctSlice(s);
    explicitSlices.push_back(saveDicom(file, EXS_LittleEndianExplicit));
  }
  seed("dicom_series", "explicit_le_1.dcm", explicitSlices[0]);
  seed("dicom_series", "explicit_le_3.dcm", joinParts(explicitSlices));
  {
    DcmFileFormat file = ctSlice(base);
    seed("dicom_series", "implicit_le.dcm", saveDicom(file, EXS_LittleEndianImplicit));
  }
  {
    DcmFileFormat file = ctSlice(base);
    seed("dicom_series", "explicit_be.dcm", saveDicom(file, EXS_BigEndianExplicit));
  }
  {
    SliceSpec s = base;
    s.bitsAllocated = 8;
    s.signedPixels = false;
    DcmFileFormat file = ctSlice(s);
    seed("dicom_series", "uint8.dcm", saveDicom(file, EXS_LittleEndianExplicit));
  }
  {
    SliceSpec s = base;
    s.signedPixels = false;
    DcmFileFormat file = ctSlice(s);
    seed("dicom_series", "rle.dcm", saveDicom(file, EXS_RLELossless));
  }
  {
    SliceSpec s = base;
    s.signedPixels = false;
    DcmFileFormat file = ctSlice(s);
    const DJ_RPLossless lossless;
    seed("dicom_series", "jpeg_lossless.dcm", saveDicom(file, EXS_JPEGProcess14SV1, &lossless));
  }
  {
    SliceSpec s = base;
    s.signedPixels = false;
    DcmFileFormat file = ctSlice(s);
    const DJLSRepresentationParameter lossless(2, OFTrue);
    seed("dicom_series", "jpeg_ls.dcm", saveDicom(file, EXS_JPEGLSLossless, &lossless));
  }
  {
    SliceSpec s = base;
    s.signedPixels = false;
    std::vector<std::string> slices;
    for (int k = 0; k < 2; ++k) {
      s.z = 1.5 * k;
      slices.push_back(jpeg2000Slice(s));
    }
    seed("dicom_series", "jpeg2000_1.dcm", slices[0]);
    seed("dicom_series", "jpeg2000_2.dcm", joinParts(slices));
  }
  if (const fs::path shared = sharedData(); !shared.empty())
    seed("dicom_series", "headsq_2.dcm",
         joinParts({readAll(shared / "headsq/dicom/CTHead1.dcm"), readAll(shared / "headsq/dicom/CTHead2.dcm")}));
  DcmRLEEncoderRegistration::cleanup();
  DJLSEncoderRegistration::cleanup();
  DJEncoderRegistration::cleanup();
}

// ---------------------------------------------------------------------------------------------
// [seg]

// A binary DICOM SEG of `segments` segments on `frames` positions, rows × columns pixels.
std::string segFile(Uint16 rows, Uint16 columns, int segments, int frames) {
  DcmSegmentation* raw = nullptr;
  IODGeneralEquipmentModule::EquipmentInfo equipment("Anatomy Tutor", "fuzz seeds", "1", "0.1");
  ContentIdentificationMacro content("1", "SEED", "fuzz seed", "Anatomy Tutor");
  if (DcmSegmentation::createBinarySegmentation(raw, rows, columns, equipment, content).bad()) return {};
  std::unique_ptr<DcmSegmentation> seg(raw);
  seg->getPatient().setPatientName("Seed^Fuzz");
  seg->getPatient().setPatientID("SEED");
  char uid[100];
  seg->getFrameOfReference().setFrameOfReferenceUID(dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT));
  seg->getStudy().setStudyInstanceUID(dcmGenerateUniqueIdentifier(uid, SITE_STUDY_UID_ROOT));
  seg->getSeries().setSeriesInstanceUID(dcmGenerateUniqueIdentifier(uid, SITE_SERIES_UID_ROOT));
  seg->getSeries().setSeriesNumber("1");

  const char* names[] = {"Liver", "Spleen", "Kidney", "Aorta"};
  std::vector<Uint16> numbers;
  for (int s = 0; s < segments; ++s) {
    DcmSegment* segment = nullptr;
    CodeSequenceMacro category("123037004", "SCT", "Anatomical Structure");
    CodeSequenceMacro type("10200004", "SCT", names[s % 4]);
    if (DcmSegment::create(segment, names[s % 4], category, type, DcmSegTypes::SAT_MANUAL).bad()) return {};
    segment->setRecommendedDisplayCIELabValue(Uint16(20000 + 9000 * s), 40000, 30000);
    Uint16 number = 0;
    if (seg->addSegment(segment, number).bad()) return {};
    numbers.push_back(number);
  }
  const std::string dimensions = dcmGenerateUniqueIdentifier(uid, SITE_INSTANCE_UID_ROOT);
  seg->getDimensions().addDimensionIndex(DCM_ReferencedSegmentNumber, dimensions.c_str(),
                                         DCM_SegmentIdentificationSequence, "ReferencedSegmentNumber");
  seg->getDimensions().addDimensionIndex(DCM_ImagePositionPatient, dimensions.c_str(), DCM_PlanePositionSequence,
                                         "ImagePositionPatient");
  FGPixelMeasures measures;
  measures.setPixelSpacing("0.75\\0.75");
  measures.setSliceThickness("2");
  measures.setSpacingBetweenSlices("2");
  seg->addForAllFrames(measures);
  FGPlaneOrientationPatient orientation;
  orientation.setImageOrientationPatient("1", "0", "0", "0", "1", "0");
  seg->addForAllFrames(orientation);
  const std::size_t pixels = std::size_t(rows) * columns;
  for (int f = 0; f < frames; ++f)
    for (std::size_t s = 0; s < numbers.size(); ++s) {
      std::vector<Uint8> mask(pixels);
      for (std::size_t p = 0; p < pixels; ++p) mask[p] = Uint8(((p + std::size_t(f) + s) % 3) == 0);
      FGPlanePosPatient* position = FGPlanePosPatient::createMinimal("-3", "-3", std::to_string(2 * f).c_str());
      FGFrameContent* frameContent = new FGFrameContent();
      frameContent->setStackID("1");
      frameContent->setInStackPositionNumber(Uint32(f + 1));
      frameContent->setDimensionIndexValues(numbers[s], 0);
      frameContent->setDimensionIndexValues(Uint32(f + 1), 1);
      OFVector<FGBase*> perFrame{position, frameContent};
      const OFCondition added = seg->addFrame(mask.data(), numbers[s], perFrame);
      delete position;
      delete frameContent;
      if (added.bad()) return {};
    }
  const fs::path path = outRoot / ".tmp-seg.dcm";
  const OFCondition saved = seg->saveFile(path.c_str());
  if (saved.bad()) {
    std::fprintf(stderr, "at_fuzz_seeds: DCMTK cannot write the SEG (%s)\n", saved.text());
    return {};
  }
  std::string bytes = readAll(path);
  fs::remove(path);
  return bytes;
}

void dicomSegSeeds() {
  seed("dicom_seg", "one_segment.dcm", segFile(6, 5, 1, 3));
  seed("dicom_seg", "three_segments.dcm", segFile(4, 8, 3, 2));
}

// ---------------------------------------------------------------------------------------------
// [png]

// A PNG of any colour type through libpng directly (writePng writes 8-bit RGB only).
std::string pngFile(int width, int height, int colourType, int bitDepth, bool interlaced, bool transparency) {
  const fs::path path = outRoot / ".tmp.png";
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) return {};
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return {};
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), bitDepth, colourType,
               interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
               PNG_FILTER_TYPE_DEFAULT);
  if (colourType == PNG_COLOR_TYPE_PALETTE) {
    png_color palette[4] = {{0, 0, 0}, {255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
    png_set_PLTE(png, info, palette, 4);
  }
  if (transparency) {
    png_byte alpha[2] = {0, 128};
    png_color_16 grey{};
    png_set_tRNS(png, info, alpha, colourType == PNG_COLOR_TYPE_PALETTE ? 2 : 0, &grey);
  }
  png_write_info(png, info);
  const int channels = colourType == PNG_COLOR_TYPE_RGB ? 3 : colourType == PNG_COLOR_TYPE_RGBA ? 4
                       : colourType == PNG_COLOR_TYPE_GRAY_ALPHA                             ? 2
                                                                                             : 1;
  const std::size_t rowBytes = (std::size_t(width) * std::size_t(channels) * std::size_t(bitDepth) + 7) / 8;
  std::vector<png_byte> row(rowBytes);
  const int passes = interlaced ? png_set_interlace_handling(png) : 1;
  for (int pass = 0; pass < passes; ++pass)
    for (int y = 0; y < height; ++y) {
      for (std::size_t i = 0; i < rowBytes; ++i) row[i] = png_byte((i * 29 + std::size_t(y) * 7) & 0xff);
      if (colourType == PNG_COLOR_TYPE_PALETTE)
        for (std::size_t i = 0; i < rowBytes; ++i) row[i] &= bitDepth == 8 ? 0x03 : 0x55;
      png_write_row(png, row.data());
    }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
  std::string bytes = readAll(path);
  fs::remove(path);
  return bytes;
}

void pngSeeds() {
  RgbImage rgb(5, 4);
  for (std::size_t i = 0; i < rgb.rgb.size(); ++i) rgb.rgb[i] = std::uint8_t(i * 11);
  seed("png", "rgb8.png", bytesOfWritten("rgb.png", [&](const std::string& p) { return writePng(p, rgb); }));
  seed("png", "grey1.png", pngFile(9, 3, PNG_COLOR_TYPE_GRAY, 1, false, false));
  seed("png", "grey16_interlaced.png", pngFile(6, 6, PNG_COLOR_TYPE_GRAY, 16, true, false));
  seed("png", "palette_trns.png", pngFile(4, 4, PNG_COLOR_TYPE_PALETTE, 8, false, true));
  seed("png", "palette2.png", pngFile(7, 2, PNG_COLOR_TYPE_PALETTE, 2, false, false));
  seed("png", "grey_alpha.png", pngFile(3, 3, PNG_COLOR_TYPE_GRAY_ALPHA, 8, false, false));
  seed("png", "rgba16.png", pngFile(3, 2, PNG_COLOR_TYPE_RGBA, 16, false, false));
}

// ---------------------------------------------------------------------------------------------
// [inv3]

// An InVesalius project's bytes, written with libarchive like the loader tests do.
std::string inv3File(const std::vector<test::TarMember>& members, bool gzip) {
  const fs::path path = outRoot / ".tmp-project.inv3";
  test::writeTar(path, members, gzip);
  std::string bytes = readAll(path);
  std::error_code ec;
  fs::remove(path, ec);
  return bytes;
}

void inv3Seeds() {
  const test::Inv3Plist plist;
  const std::string matrix = test::inv3Matrix();
  // Plain tars first: mutations of a gzip stream mostly stop at its checksum, those of a tar
  // reach the property list and the matrix.
  seed("inv3", "plain.inv3", inv3File({{"p/main.plist", plist.xml()}, {"p/matrix.dat", matrix}}, false));
  seed("inv3", "matrix_first.inv3", inv3File({{"p/matrix.dat", matrix}, {"p/main.plist", plist.xml()}}, false));
  seed("inv3", "gzip.inv3", inv3File({{"p/main.plist", plist.xml()}, {"p/matrix.dat", matrix}}, true));
  test::Inv3Plist floats;
  floats.matrix["dtype"] = "<string>float32</string>";
  floats.matrix["shape"] = "<array><integer>2</integer><integer>2</integer><integer>3</integer></array>";
  std::string floatMatrix;
  for (int i = 0; i < 12; ++i) {
    const float v = -1000.0F + 150.5F * float(i);
    floatMatrix.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  seed("inv3", "float32.inv3", inv3File({{"p/main.plist", floats.xml()}, {"p/matrix.dat", floatMatrix}}, false));
  // A mask member beside the image, as InVesalius writes it (the loader skips it).
  seed("inv3", "with_mask.inv3",
       inv3File({{"p/main.plist", plist.xml()}, {"p/mask_0.plist", "<plist version=\"1.0\"><dict/></plist>"},
                 {"p/matrix.dat", matrix}},
                false));
}

// ---------------------------------------------------------------------------------------------
// [json]

// Long tables of fuzz::kLongCsvStudy as `study export` writes them: two participants, one with
// unmeasured viewing, a comment with quotes, a comma, a line break and a formula character, and
// render quality on some rows; the same without the quality columns (older exports).
void studyLongCsvSeeds() {
  std::vector<quiz::StudyResponseRow> rows;
  const char* structures[] = {"incus", "cochlea", "stapes"};
  for (int p = 0; p < 2; ++p)
    for (int s = 0; s < 3; ++s)
      for (const char* item : {"shape", "context"}) {
        quiz::StudyResponseRow r;
        r.participantId = p == 0 ? "P1" : "lab2-p_7";
        r.group = p == 0 ? "medical" : "non-medical";
        r.session = p + 1;
        r.structure = structures[(s + p) % 3];
        r.item = item;
        r.aCondition = (s + p) % 2 == 0 ? "wdt" : "bare";
        r.ratingAb = 1 + (s * 2 + p) % 5;
        r.rating = r.aCondition == "wdt" ? r.ratingAb : 6 - r.ratingAb;
        r.presentationOrder = s + 1;
        r.presetA = r.structure + (r.aCondition == "wdt" ? "_wdt" : "_bare");
        r.presetB = r.structure + (r.aCondition == "wdt" ? "_bare" : "_wdt");
        r.t = 0.5;
        r.alpha = 1.25;
        r.beta = -0.5;
        r.viewingMeasured = p == 0;
        r.viewMsA = p == 0 ? 3120 : 0;
        r.viewMsB = p == 0 ? 2875 : 0;
        r.toggles = p == 0 ? 4 : 0;
        r.responseMs = 850 + s;
        r.timestampUtc = "2026-11-22T05:0" + std::to_string(s) + ":1" + std::to_string(p) + "Z";
        r.appVersion = "0.9.0";
        r.comment = s == 1 ? "=clearer, \"sharper\"\nthan B" : "";
        r.participantComplete = p == 0;
        if (p == 0) {
          r.qualityLevel = 2;
          r.qualityFullLevel = 2;
          r.qualityScale = 0.5;
          r.settleMs = 1690;
        }
        rows.push_back(r);
      }
  const std::string table = quiz::responsesLongCsv(rows);
  seed("study_long_csv", "two_participants.csv", table);
  std::string older;
  for (auto record : quiz::parseCsv(table)) {
    record.resize(22);
    std::vector<std::string> cells;
    for (const auto& cell : record) cells.push_back(quiz::csvQuoted(cell));
    older += quiz::csvRecord(cells);
  }
  seed("study_long_csv", "without_quality.csv", older);
}

void jsonSeeds() {
  const fs::path data = fs::path(AT_SOURCE_DIR) / "data";
  for (const auto& entry : fs::directory_iterator(data / "presets"))
    if (entry.path().extension() == ".json") seed("preset", entry.path().filename().string(), readAll(entry.path()));
  const std::string course = readAll(data / "courses" / "temporal_bone.json");
  seed("course", "temporal_bone.json", course);
  seed("course", "minimal.json",
       R"({"schema": 1, "id": "c", "title": "C", "dataset": "phantom", "lessons": [{"id": "l", "title": "L",)"
       R"( "steps": [{"kind": "show", "structure": "cochlea"}]}]})");
  seed("study_protocol", "paper_survey.json", readAll(data / "studies" / "paper_survey.json"));
  studyLongCsvSeeds();

  // Every question of the default course, as questionToJson stores it.
  if (auto parsed = lessons::parseCourseJson(course, "temporal_bone.json")) {
    int n = 0;
    for (const auto& lesson : parsed->lessons)
      for (const auto& step : lesson.steps)
        if (step.kind == lessons::StepKind::Question)
          seed("question", "question_" + std::to_string(n++) + ".json", lessons::questionToJson(step.question));
  } else {
    std::fprintf(stderr, "at_fuzz_seeds: %s\n", parsed.error().message.c_str());
  }
  seed("answer", "answers.jsonl",
       "{\"choice\": 2}\n{\"text\": \"cochlea\"}\n{\"pick\": \"stapes\", \"distance_mm\": 1.5}\n{\"pick\": null}\n"
       "{\"order\": [\"incus\", \"malleus\"]}\n");
  seed("label_names", "small.json", R"({"1": "liver", "2": "kidney_right", "65535": "last"})");
  if (const fs::path shared = sharedData(); !shared.empty())
    seed("label_names", "totalsegmentator.json", readAll(shared / "totalsegmentator/labels.json"));
}

// ---------------------------------------------------------------------------------------------
// [seg.nrrd]

void segNrrdSeeds() {
  // writeSegNrrd's output: uint8 labels, and uint16 when a label is 256 or more.
  for (const bool wide : {false, true}) {
    Geometry g;
    g.dims = {4, 3, 2};
    g.spacingMm = {0.8, 0.9, 2.5};
    g.originMm = {-10, 20, 5};
    LabelMap labels(g);
    const std::uint16_t second = wide ? 300 : 2;
    for (std::size_t n = 0; n < labels.voxels.size(); ++n) labels.voxels[n] = n % 3 == 0 ? 0 : n % 3 == 1 ? 1 : second;
    std::vector<Structure> structures(2);
    structures[0].label = 1;
    structures[0].id = "liver";
    structures[0].displayName = "Liver";
    structures[0].colour = {0.8f, 0.3f, 0.2f};
    structures[1].label = second;
    structures[1].id = "spleen";
    structures[1].displayName = "Spleen";
    seed("seg_nrrd", wide ? "written_uint16.seg.nrrd" : "written_uint8.seg.nrrd",
         bytesOfWritten("labels.seg.nrrd", [&](const std::string& p) { return writeSegNrrd(p, labels, structures); }));
  }
  // Two layers of overlapping segments, as Slicer writes them (values are per layer).
  const std::string header =
      "NRRD0004\ntype: unsigned char\ndimension: 4\nspace: left-posterior-superior\nsizes: 2 3 2 2\n"
      "space directions: none (1,0,0) (0,1,0) (0,0,2)\nkinds: list domain domain domain\n"
      "encoding: raw\nspace origin: (0,0,0)\n"
      "Segment0_ID:=liver\nSegment0_Name:=liver\nSegment0_Color:=0.9 0.5 0.4\nSegment0_LabelValue:=1\n"
      "Segment0_Layer:=0\nSegment0_Extent:=0 2 0 1 0 1\n"
      "Segment1_ID:=tumour\nSegment1_Name:=tumour\nSegment1_Color:=0.9 0.9 0.1\nSegment1_LabelValue:=1\n"
      "Segment1_Layer:=1\n\n";
  const std::string layer0 = std::string("\1\1\0\0\0\0\1\0\0\0\0\0", 12);
  const std::string layer1 = std::string("\0\1\1\0\0\0\0\0\0\0\0\1", 12);
  std::string data;
  for (std::size_t v = 0; v < layer0.size(); ++v) data += layer0[v], data += layer1[v];
  seed("seg_nrrd", "two_layers.seg.nrrd", header + data);
  if (const fs::path shared = sharedData(); !shared.empty())
    for (const char* name : {"dcmqi/spine_seg_label5.nrrd", "dcmqi/heart_seg.nrrd"})
      seed("seg_nrrd", fs::path(name).filename().string(), readAll(shared / name));
}

// Seeds files of the segment command: the schema's example, a RAS one with the threshold fields,
// and what seedsToJson writes.
void segmentSeedsSeeds() {
  const std::string example = R"({"schema": 1, "space": "LPS",
  "labels": [{"value": 0, "name": "background"},
             {"value": 5, "name": "liver", "colour": [0.86, 0.55, 0.39], "range": [-50, 250], "min_diameter_mm": 3}],
  "strokes": [{"label": "liver", "radius_mm": 2, "points": [[0, 0, 4], [5, 3, 8], [6, -4, 12]]},
              {"label": 0, "points": [[-10, -12, 2]]}],
  "grow": {"weight": "gradient", "window": [-160, 240], "base": 0.05}})";
  seed("segment_seeds", "example.json", example);
  seed("segment_seeds", "ras_dots.json",
       R"({"space": "RAS", "labels": [{"value": 0, "name": "background"}, {"value": 1, "name": "a"}, {"value": 2, "name": "b"}],)"
       R"( "strokes": [{"label": "a", "points": [[1, 1, 1]]}, {"label": 2, "points": [[-3, 2, 10]]}, {"label": 0, "points": [[8, 9, 14]]}],)"
       R"( "grow": {"weight": "ascent"}})");
  if (auto parsed = segment::parseSeeds(example, "example.json")) {
    seed("segment_seeds", "written.json", segment::seedsToJson(*parsed));
  } else {
    std::fprintf(stderr, "at_fuzz_seeds: %s\n", parsed.error().message.c_str());
    failed = true;
  }
  const fs::path data = fs::path(AT_SOURCE_DIR) / "data" / "segmentations";
  std::error_code ec;
  if (fs::is_directory(data, ec))
    for (const auto& entry : fs::recursive_directory_iterator(data, ec))
      if (entry.path().filename() == "seeds.json")
        seed("segment_seeds", entry.path().parent_path().filename().string() + "_seeds.json", readAll(entry.path()));
}

// ---------------------------------------------------------------------------------------------
// [package]

// The entries of a tar as fuzz_package's assembled input: the manifest first, then "NAME\nCONTENT"
// for every other entry ("" when libarchive cannot read it).
std::string assembledParts(const std::string& tar) {
  std::unique_ptr<archive, int (*)(archive*)> a(archive_read_new(), archive_read_free);
  archive_read_support_format_tar(a.get());
  if (archive_read_open_memory(a.get(), tar.data(), tar.size()) != ARCHIVE_OK) return "";
  std::string manifest;
  std::vector<std::string> parts;
  archive_entry* entry = nullptr;
  while (archive_read_next_header(a.get(), &entry) == ARCHIVE_OK) {
    const std::string name = archive_entry_pathname(entry);
    std::string content(std::size_t(archive_entry_size(entry)), '\0');
    if (archive_read_data(a.get(), content.data(), content.size()) != la_ssize_t(content.size())) return "";
    if (name == "manifest.json") manifest = content;
    else parts.push_back(name + "\n" + content);
  }
  if (manifest.empty()) return "";
  parts.insert(parts.begin(), manifest);
  return joinParts(parts);
}

// Writes a package with the project's writer; returns its bytes ("" on failure, reported).
std::string packageFile(const package::PackageInput& input) {
  const fs::path path = outRoot / ".tmp-course.atcourse";
  auto ok = package::writePackage(path, input);
  if (!ok) {
    std::fprintf(stderr, "at_fuzz_seeds: %s\n", ok.error().message.c_str());
    return "";
  }
  std::string bytes = readAll(path);
  fs::remove(path);
  return bytes;
}

void packageSeeds() {
  const fs::path data = fs::path(AT_SOURCE_DIR) / "data";
  // The shipped course on the built-in phantom with the presets it uses.
  auto course = lessons::parseCourseJson(readAll(data / "courses" / "temporal_bone.json"), "temporal_bone.json");
  if (!course) {
    std::fprintf(stderr, "at_fuzz_seeds: %s\n", course.error().message.c_str());
    failed = true;
    return;
  }
  package::PackageInput builtin;
  builtin.course = *course;
  builtin.dataset.name = course->datasetId;
  builtin.createdBy = "at_fuzz_seeds";
  for (const char* id : {"cochlea_wdt", "vestibule_wdt"}) {
    const fs::path file = data / "presets" / (std::string(id) + ".json");
    auto preset = render::loadPreset(file);
    if (!preset) {
      std::fprintf(stderr, "at_fuzz_seeds: %s\n", preset.error().message.c_str());
      failed = true;
      return;
    }
    builtin.presets.push_back({id, *preset, readAll(file)});
  }
  const std::string builtinTar = packageFile(builtin);
  seed("package", "builtin.atcourse", builtinTar);
  seed("package", "builtin.parts", assembledParts(builtinTar));

  // A small course on a 16³ phantom included in the package, with its structures and labels.
  auto phantom = openBuiltinDataset("phantom:16");
  auto small = lessons::parseCourseJson(
      R"({"schema": 1, "id": "small", "title": "Small", "dataset": "small", "version": 2, "lessons": [{"id": "l",)"
      R"( "title": "L", "steps": [{"kind": "show", "structure": "cochlea", "preset": "cochlea_wdt", "view": "superior",)"
      R"( "title": "T", "text": "X"},)"
      R"( {"kind": "question", "question": {"id": "q", "kind": "name", "prompt": "Name it", "target": "cochlea"}}]}]})",
      "small.json");
  if (!phantom || !small) {
    std::fprintf(stderr, "at_fuzz_seeds: %s\n", (!phantom ? phantom.error() : small.error()).message.c_str());
    failed = true;
    return;
  }
  phantom->id = "small";
  const fs::path files = outRoot / ".tmp-package-files";
  fs::create_directories(files);
  auto written = package::writeDatasetFiles(*phantom, files, true);
  if (!written) {
    std::fprintf(stderr, "at_fuzz_seeds: %s\n", written.error().message.c_str());
    failed = true;
    return;
  }
  package::PackageInput included;
  included.course = *small;
  included.presets.push_back(builtin.presets.front());
  included.dataset.name = "small";
  included.dataset.source = package::VolumeSource::Included;
  included.dataset.geometry = phantom->volume.geometry;
  included.dataset.sourceVolumeChecksum = "sha256:" + std::string(64, 'a');
  // Three structures (the phantom's full list would make every execution parse a long document).
  for (const Structure& s : phantom->structures)
    if (s.id == "cochlea" || s.id == "vestibule" || s.id == "stapes") included.structures.push_back(s);
  included.volumeFile = written->volume;
  included.labelsFile = written->labels;
  included.createdBy = "at_fuzz_seeds";
  const std::string includedTar = packageFile(included);
  seed("package", "included.atcourse", includedTar);
  seed("package", "included.parts", assembledParts(includedTar));
  // The same course by reference to a volume the importer supplies (no data files).
  package::PackageInput reference = included;
  reference.dataset.source = package::VolumeSource::Reference;
  reference.dataset.referenceFileName = "Small.inv3";
  reference.dataset.referenceNote = "from the fuzz seeds";
  reference.volumeFile.clear();
  reference.labelsFile.clear();
  const std::string referenceTar = packageFile(reference);
  seed("package", "reference.atcourse", referenceTar);
  seed("package", "reference.parts", assembledParts(referenceTar));
  // Read with a rescale (format version 2): a referenced scan the author read with options, an MR.
  reference.dataset.reading = package::VolumeReading{IntensityChoice::Plain, -1024.0, 0.5, false, "MR"};
  const std::string readingTar = packageFile(reference);
  seed("package", "reading.atcourse", readingTar);
  seed("package", "reading.parts", assembledParts(readingTar));
  fs::remove_all(files);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: at_fuzz_seeds OUT_DIR\n");
    return 2;
  }
  OFLog::configure(std::getenv("AT_SEEDS_DCMTK_LOG") ? OFLogger::WARN_LOG_LEVEL : OFLogger::FATAL_LOG_LEVEL);
  outRoot = argv[1];
  fs::create_directories(outRoot);
  niftiSeeds();
  nrrdSeeds();
  segNrrdSeeds();
  segmentSeedsSeeds();
  dicomSeriesSeeds();
  dicomSegSeeds();
  pngSeeds();
  inv3Seeds();
  jsonSeeds();
  packageSeeds();
  std::printf("at_fuzz_seeds: %d seeds in %s%s\n", written, outRoot.c_str(),
              sharedData().empty() ? " (../shared/data absent: generated seeds only)" : "");
  return failed ? 1 : 0;
}
