// DICOM CT series from a folder (DCMTK; JPEG 2000 through OpenJPEG).
//
// Sections:
//   1. DCMTK set-up (codec registration, logging) and small attribute readers
//   2. Slice headers: scanning a folder, grouping by series
//   3. JPEG 2000 frames through OpenJPEG
//   4. Pixel data of one slice → rescaled values
//   5. loadDicomSeries
//
// Only geometry and pixel attributes are read; patient and study attributes are never looked at,
// so nothing identifying can reach the LoadedImage.
#include "volume/dicom_series.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include <dcmtk/config/osconfig.h>
#include <dcmtk/dcmdata/dccodec.h>
#include <dcmtk/dcmdata/dcdeftag.h>
#include <dcmtk/dcmdata/dcfilefo.h>
#include <dcmtk/dcmdata/dcmetinf.h>
#include <dcmtk/dcmdata/dcpixel.h>
#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dcpxitem.h>
#include <dcmtk/dcmdata/dcrledrg.h>
#include <dcmtk/dcmdata/dcuid.h>
#include <dcmtk/dcmdata/dcxfer.h>
#include <dcmtk/dcmjpeg/djdecode.h>
#include <dcmtk/dcmjpls/djdecode.h>
#include <dcmtk/oflog/oflog.h>
#include <openjpeg.h>

#include "../io/load_limits.h"
#include "core/parallel_rows.h"
#include "core/printable_text.h"
#include "core/regular_file.h"
#include "dicom_support.h"

namespace fs = std::filesystem;

namespace at {

// ─── 1. DCMTK set-up and attribute readers ──────────────────────────────────────────────────────

namespace dicom {

namespace {

// Owns the process-wide registration of DCMTK's decoders.
class DecoderRegistration {
 public:
  DecoderRegistration() {
    OFLog::configure(OFLogger::FATAL_LOG_LEVEL);
    DJDecoderRegistration::registerCodecs();
    DJLSDecoderRegistration::registerCodecs();
    DcmRLEDecoderRegistration::registerCodecs();
  }
  ~DecoderRegistration() {
    DcmRLEDecoderRegistration::cleanup();
    DJLSDecoderRegistration::cleanup();
    DJDecoderRegistration::cleanup();
  }
  DecoderRegistration(const DecoderRegistration&) = delete;
  DecoderRegistration& operator=(const DecoderRegistration&) = delete;
};

}  // namespace

void ensureDcmtkReady() { static DecoderRegistration registration; }

Result<std::string> readSeriesInstanceUid(const std::string& path) {
  ensureDcmtkReady();
  DcmFileFormat file;
  const OFCondition status = file.loadFile(OFFilename(path.c_str()), EXS_Unknown, EGL_noChange, 256);
  if (status.bad()) return fail(path + ": cannot read DICOM file (" + status.text() + ")");
  OFString uid;
  file.getDataset()->findAndGetOFString(DCM_SeriesInstanceUID, uid);
  return std::string(uid.c_str());
}

}  // namespace dicom

bool looksLikeDicomFile(const std::string& path) {
  auto file = openRegularFile(path, path);
  if (!file) return false;
  auto header = readFileRange(*file, 0, 132, path);
  return header && header->size() == 132 && header->compare(128, 4, "DICM") == 0;
}

namespace {

// True if a regular file starts with the DICOM preamble; an error if it cannot be read at all.
Result<bool> hasDicomPreamble(const fs::path& path) {
  auto file = openRegularFile(path.string(), path.filename().string());
  if (!file) return tl::unexpected(file.error());
  auto header = readFileRange(*file, 0, 132, path.filename().string());
  if (!header) return tl::unexpected(header.error());
  return header->size() == 132 && header->compare(128, 4, "DICM") == 0;
}

using dicom::formatNumber;

std::string stringOf(DcmItem& item, const DcmTagKey& tag) {
  OFString value;
  item.findAndGetOFString(tag, value);
  return value.c_str();
}

// Reads `count` numbers of a DS/FD attribute; nullopt if absent or short.
template <std::size_t N>
std::optional<std::array<double, N>> numbersOf(DcmItem& item, const DcmTagKey& tag) {
  std::array<double, N> values{};
  for (std::size_t i = 0; i < N; ++i) {
    Float64 v = 0;
    if (item.findAndGetFloat64(tag, v, static_cast<unsigned long>(i)).bad() || !std::isfinite(v)) return std::nullopt;
    values[i] = v;
  }
  return values;
}

std::optional<long> integerOf(DcmItem& item, const DcmTagKey& tag) {
  Uint16 u = 0;
  if (item.findAndGetUint16(tag, u).good()) return long(u);
  Sint32 s = 0;
  if (item.findAndGetSint32(tag, s).good()) return long(s);
  return std::nullopt;
}

// ─── 2. Slice headers ───────────────────────────────────────────────────────────────────────────

struct SliceHeader {
  fs::path file;
  std::string name;  // file name, for messages
  std::string seriesUid;
  E_TransferSyntax transferSyntax = EXS_Unknown;
  std::string transferSyntaxUid;
  int rows = 0, columns = 0;
  long frames = 1;
  int samplesPerPixel = 1;
  std::string photometric;
  int bitsAllocated = 16, bitsStored = 16, highBit = 15, pixelRepresentation = 0;
  double slope = 1, intercept = 0;
  bool rescaleGiven = false;  // RescaleSlope or RescaleIntercept present
  std::string modality;
  std::optional<std::array<double, 3>> position;
  std::optional<std::array<double, 6>> orientation;
  std::optional<std::array<double, 2>> pixelSpacing;  // row spacing (between rows), column spacing
  double sliceThickness = 0, spacingBetweenSlices = 0;
  std::uint64_t fileBytes = 0;
  std::uint32_t pixelDataLength = 0;  // as the PixelData element says (undefined length: encapsulated)
  std::string pixelDataProblem;       // a PixelData element that is not OB/OW pixel data
};

enum class FileKind { Image, NotAnImage };

// Reads one file's header without loading its pixel data.
Result<std::pair<FileKind, SliceHeader>> readSliceHeader(const fs::path& file) {
  auto regular = openRegularFile(file.string(), file.filename().string());
  if (!regular) return tl::unexpected(regular.error());
  DcmFileFormat dicomFile;
  const OFCondition status = dicomFile.loadFile(OFFilename(file.c_str()), EXS_Unknown, EGL_noChange, 4096);
  if (status.bad()) return fail(file.filename().string() + ": cannot read DICOM file (" + status.text() + ")");
  DcmDataset& data = *dicomFile.getDataset();
  SliceHeader h;
  h.file = file;
  h.name = file.filename().string();

  std::string sopClass = stringOf(data, DCM_SOPClassUID);
  if (sopClass.empty()) sopClass = stringOf(*dicomFile.getMetaInfo(), DCM_MediaStorageSOPClassUID);
  if (!data.tagExists(DCM_PixelData) || sopClass == UID_SegmentationStorage) return std::pair{FileKind::NotAnImage, h};

  h.fileBytes = regular->sizeBytes;
  DcmElement* pixelElement = nullptr;
  if (data.findAndGetElement(DCM_PixelData, pixelElement).good() && pixelElement) {
    h.pixelDataLength = pixelElement->getLengthField();
    // DCMTK reads (7FE0,0010) as DcmPixelData only with the VR OB or OW (or implicit VR); any
    // other VR in the file gives another element class, which the pixel reader must not cast.
    if (!dynamic_cast<DcmPixelData*>(pixelElement))
      h.pixelDataProblem = std::string("PixelData has the value representation ") +
                           DcmVR(pixelElement->getVR()).getVRName() + ", not OB or OW";
  }
  h.seriesUid = stringOf(data, DCM_SeriesInstanceUID);
  h.transferSyntax = data.getOriginalXfer();
  h.transferSyntaxUid = DcmXfer(h.transferSyntax).getXferID();
  h.rows = int(integerOf(data, DCM_Rows).value_or(0));
  h.columns = int(integerOf(data, DCM_Columns).value_or(0));
  h.frames = integerOf(data, DCM_NumberOfFrames).value_or(1);
  h.samplesPerPixel = int(integerOf(data, DCM_SamplesPerPixel).value_or(1));
  h.photometric = stringOf(data, DCM_PhotometricInterpretation);
  h.bitsAllocated = int(integerOf(data, DCM_BitsAllocated).value_or(0));
  h.bitsStored = int(integerOf(data, DCM_BitsStored).value_or(h.bitsAllocated));
  h.highBit = int(integerOf(data, DCM_HighBit).value_or(h.bitsStored - 1));
  h.pixelRepresentation = int(integerOf(data, DCM_PixelRepresentation).value_or(0));
  if (auto v = numbersOf<1>(data, DCM_RescaleSlope)) h.slope = (*v)[0], h.rescaleGiven = true;
  if (auto v = numbersOf<1>(data, DCM_RescaleIntercept)) h.intercept = (*v)[0], h.rescaleGiven = true;
  h.modality = stringOf(data, DCM_Modality);
  h.position = numbersOf<3>(data, DCM_ImagePositionPatient);
  h.orientation = numbersOf<6>(data, DCM_ImageOrientationPatient);
  h.pixelSpacing = numbersOf<2>(data, DCM_PixelSpacing);
  if (auto v = numbersOf<1>(data, DCM_SliceThickness)) h.sliceThickness = (*v)[0];
  if (auto v = numbersOf<1>(data, DCM_SpacingBetweenSlices)) h.spacingBetweenSlices = (*v)[0];
  return std::pair{FileKind::Image, h};
}

std::string seriesLabel(const std::string& uid) { return uid.empty() ? "(no SeriesInstanceUID)" : uid; }

// Checks the attributes one slice needs before any pixel is decoded.
Status checkSliceHeader(const SliceHeader& h) {
  if (h.frames > 1)
    return fail(h.name + ": multi-frame images are not supported (" + std::to_string(h.frames) + " frames)");
  if (h.rows <= 0 || h.columns <= 0) return fail(h.name + ": missing or zero Rows/Columns");
  if (!h.position) return fail(h.name + ": missing ImagePositionPatient");
  if (!h.orientation) return fail(h.name + ": missing ImageOrientationPatient");
  if (!h.pixelSpacing) return fail(h.name + ": missing PixelSpacing");
  if ((*h.pixelSpacing)[0] <= 0 || (*h.pixelSpacing)[1] <= 0)
    return fail(h.name + ": PixelSpacing must be positive (" + formatNumber((*h.pixelSpacing)[0]) + "\\" +
                formatNumber((*h.pixelSpacing)[1]) + ")");
  if (h.samplesPerPixel != 1 || (h.photometric != "MONOCHROME2" && h.photometric != "MONOCHROME1"))
    return fail(h.name + ": colour images are not supported (PhotometricInterpretation " + h.photometric + ", " +
                std::to_string(h.samplesPerPixel) + " samples per pixel)");
  if (h.bitsAllocated != 8 && h.bitsAllocated != 16)
    return fail(h.name + ": BitsAllocated " + std::to_string(h.bitsAllocated) + " is not supported (8 or 16)");
  if (h.bitsStored < 1 || h.bitsStored > h.bitsAllocated || h.highBit < h.bitsStored - 1 ||
      h.highBit >= h.bitsAllocated)
    return fail(h.name + ": inconsistent BitsStored " + std::to_string(h.bitsStored) + " / HighBit " +
                std::to_string(h.highBit) + " for BitsAllocated " + std::to_string(h.bitsAllocated));
  if (!std::isfinite(h.slope) || h.slope == 0) return fail(h.name + ": RescaleSlope must be non-zero");
  if (!h.pixelDataProblem.empty()) return fail(h.name + ": " + h.pixelDataProblem);
  // Native pixel data must exist before anything is allocated for them: the element's length must
  // cover Rows × Columns samples and the file must hold that many bytes.
  if (!DcmXfer(h.transferSyntax).isEncapsulated()) {
    const std::uint64_t need = std::uint64_t(h.rows) * std::uint64_t(h.columns) * std::uint64_t(h.bitsAllocated / 8);
    if (h.pixelDataLength == DCM_UndefinedLength || h.pixelDataLength < need)
      return fail(h.name + ": PixelData holds " +
                  (h.pixelDataLength == DCM_UndefinedLength ? std::string("encapsulated data")
                                                            : std::to_string(h.pixelDataLength) + " bytes") +
                  " but " + std::to_string(h.columns) + "x" + std::to_string(h.rows) + " × " +
                  std::to_string(h.bitsAllocated) + " bits need " + std::to_string(need));
    if (h.fileBytes < h.pixelDataLength)
      return fail(h.name + ": PixelData claims " + std::to_string(h.pixelDataLength) + " bytes but the file holds only " +
                  std::to_string(h.fileBytes) + " (file truncated?)");
  }
  return {};
}

ScalarKind storedKindOf(const SliceHeader& h) {
  if (h.bitsAllocated == 8) return h.pixelRepresentation ? ScalarKind::Int8 : ScalarKind::UInt8;
  return h.pixelRepresentation ? ScalarKind::Int16 : ScalarKind::UInt16;
}

bool isJpeg2000(const SliceHeader& h) {
  return h.transferSyntaxUid == UID_JPEG2000LosslessOnlyTransferSyntax ||
         h.transferSyntaxUid == UID_JPEG2000TransferSyntax;
}

Status checkTransferSyntax(const SliceHeader& h) {
  const DcmXfer xfer(h.transferSyntax);
  if (h.transferSyntax == EXS_Unknown) return fail(h.name + ": unknown transfer syntax");
  if (!xfer.isEncapsulated() || isJpeg2000(h)) return {};
  if (DcmCodecList::canChangeCoding(h.transferSyntax, EXS_LittleEndianExplicit)) return {};
  return fail(h.name + ": unsupported transfer syntax " + xfer.getXferName() + " (" + h.transferSyntaxUid + ")");
}

// ─── 3. JPEG 2000 through OpenJPEG ──────────────────────────────────────────────────────────────

struct MemoryStream {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  std::size_t offset = 0;
};

OPJ_SIZE_T readFromMemory(void* buffer, OPJ_SIZE_T count, void* user) {
  auto* s = static_cast<MemoryStream*>(user);
  if (s->offset >= s->size) return OPJ_SIZE_T(-1);
  const std::size_t n = std::min<std::size_t>(count, s->size - s->offset);
  std::memcpy(buffer, s->data + s->offset, n);
  s->offset += n;
  return n;
}

OPJ_OFF_T skipInMemory(OPJ_OFF_T count, void* user) {
  auto* s = static_cast<MemoryStream*>(user);
  if (count < 0) {
    const std::size_t back = std::min<std::size_t>(std::size_t(-count), s->offset);
    s->offset -= back;
    return -OPJ_OFF_T(back);
  }
  const std::size_t n = std::min<std::size_t>(std::size_t(count), s->size - s->offset);
  s->offset += n;
  return OPJ_OFF_T(n);
}

OPJ_BOOL seekInMemory(OPJ_OFF_T position, void* user) {
  auto* s = static_cast<MemoryStream*>(user);
  if (position < 0 || std::size_t(position) > s->size) return OPJ_FALSE;
  s->offset = std::size_t(position);
  return OPJ_TRUE;
}

void collectOpenJpegMessage(const char* message, void* user) {
  auto* text = static_cast<std::string*>(user);
  if (text->empty()) {
    *text = message;
    while (!text->empty() && (text->back() == '\n' || text->back() == '\r')) text->pop_back();
  }
}

struct StreamDeleter {
  void operator()(opj_stream_t* s) const { opj_stream_destroy(s); }
};
struct CodecDeleter {
  void operator()(opj_codec_t* c) const { opj_destroy_codec(c); }
};
struct ImageDeleter {
  void operator()(opj_image_t* i) const { opj_image_destroy(i); }
};

// Decodes one JPEG 2000 codestream (raw J2K or a JP2 file) holding a single-component image of the
// slice's size; returns the samples as stored values (signed per PixelRepresentation).
Result<std::vector<std::int32_t>> decodeJpeg2000(const std::vector<std::uint8_t>& bytes, const SliceHeader& h) {
  static const std::uint8_t kJp2Signature[12] = {0, 0, 0, 0x0C, 'j', 'P', ' ', ' ', 0x0D, 0x0A, 0x87, 0x0A};
  static const std::uint8_t kJ2kSignature[4] = {0xFF, 0x4F, 0xFF, 0x51};
  OPJ_CODEC_FORMAT format;
  if (bytes.size() >= 12 && std::memcmp(bytes.data(), kJp2Signature, 12) == 0)
    format = OPJ_CODEC_JP2;
  else if (bytes.size() >= 4 && std::memcmp(bytes.data(), kJ2kSignature, 4) == 0)
    format = OPJ_CODEC_J2K;
  else
    return fail(h.name + ": JPEG 2000 pixel data starts with neither a J2K codestream nor a JP2 header");

  MemoryStream source{bytes.data(), bytes.size(), 0};
  std::unique_ptr<opj_stream_t, StreamDeleter> stream(opj_stream_create(OPJ_J2K_STREAM_CHUNK_SIZE, OPJ_TRUE));
  std::unique_ptr<opj_codec_t, CodecDeleter> codec(opj_create_decompress(format));
  if (!stream || !codec) return fail(h.name + ": cannot create a JPEG 2000 decoder");
  opj_stream_set_user_data(stream.get(), &source, nullptr);
  opj_stream_set_user_data_length(stream.get(), bytes.size());
  opj_stream_set_read_function(stream.get(), readFromMemory);
  opj_stream_set_skip_function(stream.get(), skipInMemory);
  opj_stream_set_seek_function(stream.get(), seekInMemory);

  std::string openJpegError;
  opj_set_error_handler(codec.get(), collectOpenJpegMessage, &openJpegError);
  opj_dparameters_t parameters;
  opj_set_default_decoder_parameters(&parameters);
  if (!opj_setup_decoder(codec.get(), &parameters)) return fail(h.name + ": cannot set up the JPEG 2000 decoder");

  opj_image_t* rawImage = nullptr;
  const bool headerRead = opj_read_header(stream.get(), codec.get(), &rawImage);
  std::unique_ptr<opj_image_t, ImageDeleter> image(rawImage);
  if (!headerRead || !image || !opj_decode(codec.get(), stream.get(), image.get()) ||
      !opj_end_decompress(codec.get(), stream.get()))
    return fail(h.name + ": JPEG 2000 decoding failed" + (openJpegError.empty() ? "" : " (" + openJpegError + ")"));

  if (image->numcomps != 1)
    return fail(h.name + ": JPEG 2000 image has " + std::to_string(image->numcomps) + " components, expected 1");
  const opj_image_comp_t& c = image->comps[0];
  if (int(c.w) != h.columns || int(c.h) != h.rows || c.dx != 1 || c.dy != 1 || !c.data)
    return fail(h.name + ": JPEG 2000 image is " + std::to_string(c.w) + "x" + std::to_string(c.h) +
                " but the header says " + std::to_string(h.columns) + "x" + std::to_string(h.rows));
  if (int(c.prec) > h.bitsAllocated)
    return fail(h.name + ": JPEG 2000 precision " + std::to_string(c.prec) + " bits exceeds BitsAllocated " +
                std::to_string(h.bitsAllocated));

  std::vector<std::int32_t> samples(c.data, c.data + std::size_t(c.w) * c.h);
  // DICOM's PixelRepresentation governs; codestreams of signed data are sometimes marked unsigned,
  // and then hold the two's-complement bit pattern of BitsStored bits.
  if (h.pixelRepresentation == 1 && !c.sgnd) {
    const int bits = h.bitsStored;
    for (std::int32_t& v : samples)
      if (v >= (1 << (bits - 1))) v -= (1 << bits);
  } else if (h.pixelRepresentation == 0 && c.sgnd) {
    if (std::any_of(samples.begin(), samples.end(), [](std::int32_t v) { return v < 0; }))
      return fail(h.name + ": JPEG 2000 holds negative samples but PixelRepresentation says unsigned");
  }
  return samples;
}

// Concatenates the encapsulated fragments of the (single) frame.
Result<std::vector<std::uint8_t>> encapsulatedFrame(DcmPixelData& pixelData, const SliceHeader& h) {
  DcmPixelSequence* sequence = nullptr;
  if (pixelData.getEncapsulatedRepresentation(h.transferSyntax, nullptr, sequence).bad() || !sequence)
    return fail(h.name + ": no encapsulated pixel data for transfer syntax " + h.transferSyntaxUid);
  std::vector<std::uint8_t> bytes;
  // Item 0 is the basic offset table; a single-frame image owns all further fragments.
  for (unsigned long i = 1; i < sequence->card(); ++i) {
    DcmPixelItem* item = nullptr;
    if (sequence->getItem(item, i).bad() || !item) return fail(h.name + ": unreadable pixel data fragment");
    Uint8* fragment = nullptr;
    const Uint32 length = item->getLength();
    if (length == 0) continue;
    if (item->getUint8Array(fragment).bad() || !fragment)
      return fail(h.name + ": pixel data fragment " + std::to_string(i) + " cannot be read (file truncated?)");
    bytes.insert(bytes.end(), fragment, fragment + length);
  }
  if (bytes.empty()) return fail(h.name + ": encapsulated pixel data holds no fragments");
  return bytes;
}

// ─── 4. Pixel data of one slice ─────────────────────────────────────────────────────────────────

// Stored value of a raw sample: bits [highBit-bitsStored+1, highBit], sign-extended if signed.
std::int32_t storedValue(std::uint32_t raw, const SliceHeader& h) {
  const int shift = h.highBit + 1 - h.bitsStored;
  const std::uint32_t mask = h.bitsStored >= 32 ? 0xFFFFFFFFu : ((1u << h.bitsStored) - 1u);
  const std::uint32_t bits = (raw >> shift) & mask;
  if (h.pixelRepresentation == 1 && (bits >> (h.bitsStored - 1)) & 1u)
    return std::int32_t(bits) - std::int32_t(1u << h.bitsStored);
  return std::int32_t(bits);
}

// Loads one slice's pixels and writes slope·v + intercept into `out` (rows × columns floats).
Status readSlicePixels(const SliceHeader& h, float* out) {
  DcmFileFormat dicomFile;
  const OFCondition status = dicomFile.loadFile(OFFilename(h.file.c_str()));
  if (status.bad()) return fail(h.name + ": cannot read DICOM file (" + status.text() + ")");
  DcmDataset& data = *dicomFile.getDataset();
  DcmElement* element = nullptr;
  if (data.findAndGetElement(DCM_PixelData, element).bad() || !element)
    return fail(h.name + ": no pixel data");
  // The header check refused other VRs, but the file may have changed since: check again.
  auto* pixelElement = dynamic_cast<DcmPixelData*>(element);
  if (!pixelElement)
    return fail(h.name + ": PixelData has the value representation " + DcmVR(element->getVR()).getVRName() +
                ", not OB or OW");
  DcmPixelData& pixelData = *pixelElement;
  const std::size_t count = std::size_t(h.rows) * std::size_t(h.columns);

  if (isJpeg2000(h)) {
    auto bytes = encapsulatedFrame(pixelData, h);
    if (!bytes) return tl::unexpected(bytes.error());
    auto samples = decodeJpeg2000(*bytes, h);
    if (!samples) return tl::unexpected(samples.error());
    for (std::size_t i = 0; i < count; ++i) out[i] = float(h.slope * (*samples)[i] + h.intercept);
    return {};
  }

  const std::size_t bytesPerSample = std::size_t(h.bitsAllocated / 8);
  std::vector<std::uint8_t> buffer(count * bytesPerSample + 1);  // even size for DCMTK's byte swapping
  Uint32 frameSize = 0;
  if (pixelData.getUncompressedFrameSize(&data, frameSize).bad() || frameSize < count * bytesPerSample)
    return fail(h.name + ": pixel data size does not match " + std::to_string(h.columns) + "x" +
                std::to_string(h.rows) + " × " + std::to_string(h.bitsAllocated) + " bits");
  if (buffer.size() < frameSize) buffer.resize(frameSize + 1);
  Uint32 startFragment = 0;
  OFString colourModel;
  const OFCondition decoded = pixelData.getUncompressedFrame(&data, 0, startFragment, buffer.data(),
                                                             Uint32(buffer.size() & ~std::size_t(1)), colourModel);
  if (decoded.bad())
    return fail(h.name + ": cannot read pixel data (" + decoded.text() + "; file truncated or corrupt?)");
  for (std::size_t i = 0; i < count; ++i) {
    std::uint32_t raw;
    if (bytesPerSample == 2) {
      std::uint16_t word;
      std::memcpy(&word, buffer.data() + 2 * i, 2);  // DCMTK returns samples in host byte order
      raw = word;
    } else {
      raw = buffer[i];
    }
    out[i] = float(h.slope * storedValue(raw, h) + h.intercept);
  }
  return {};
}

}  // namespace

// ─── 5. loadDicomSeries ─────────────────────────────────────────────────────────────────────────

namespace {

Result<LoadedImage> readDicomSeries(const std::string& folder, const ImageLoadOptions& options) {
  dicom::ensureDcmtkReady();
  auto error = [&](const std::string& problem) { return fail(folder + ": " + problem); };

  std::error_code ec;
  if (!fs::exists(folder, ec)) return error("no such folder");
  if (!fs::is_directory(folder, ec)) return error("not a folder");

  // Files that cannot be read or whose own header is broken: an error naming the first, or, when
  // the caller asked to skip them (ImageLoadOptions::skipUnreadableFiles), a note naming them.
  std::vector<std::string> skipped;
  const auto unreadable = [&](const std::string& message) -> Status {
    if (!options.skipUnreadableFiles) return error(message + " (unreadable files can be skipped: --skip-unreadable)");
    skipped.push_back(message);
    return {};
  };

  // Scan: every regular file with the DICOM preamble; other files (READMEs, licences) are ignored.
  std::vector<fs::path> files;
  for (fs::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;  // folders, FIFOs, devices, dangling links
    auto dicom = hasDicomPreamble(it->path());
    if (!dicom) {
      if (auto ok = unreadable(dicom.error().message); !ok) return tl::unexpected(ok.error());
    } else if (*dicom) {
      files.push_back(it->path());
    }
  }
  if (ec) return error("cannot list the folder (" + ec.message() + ")");
  std::sort(files.begin(), files.end());
  if (files.empty()) return error("no DICOM files in the folder" + std::string(skipped.empty() ? "" : " that can be read"));

  std::map<std::string, std::vector<SliceHeader>> series;
  std::size_t notImages = 0;
  for (const fs::path& file : files) {
    if (detail::loadCancelled(options)) return tl::unexpected(detail::cancelledError(folder));
    auto header = readSliceHeader(file);
    if (!header) {
      if (auto ok = unreadable(header.error().message); !ok) return tl::unexpected(ok.error());
      continue;
    }
    if (header->first == FileKind::NotAnImage) {
      ++notImages;
      continue;
    }
    series[header->second.seriesUid].push_back(std::move(header->second));
  }
  if (series.empty())
    return error("no DICOM images in the folder (" + std::to_string(notImages) + " DICOM files without images)");

  // Choose the series.
  std::string chosen;
  if (!options.dicomSeriesUid.empty()) {
    if (!series.count(options.dicomSeriesUid)) {
      std::string available;
      for (const auto& [uid, slices] : series)
        available += (available.empty() ? "" : ", ") + seriesLabel(uid) + " (" + std::to_string(slices.size()) + ")";
      return error("no series with SeriesInstanceUID " + options.dicomSeriesUid + " (found " + available + ")");
    }
    chosen = options.dicomSeriesUid;
  } else {
    std::size_t most = 0;
    for (const auto& [uid, slices] : series)
      if (slices.size() > most) {
        most = slices.size();
        chosen = uid;
      }
  }
  std::vector<SliceHeader>& slices = series[chosen];
  // Each slice's own header (of the chosen series only: a colour localizer beside it is no error).
  for (auto it = slices.begin(); it != slices.end();) {
    Status ok = checkSliceHeader(*it);
    if (ok) ok = checkTransferSyntax(*it);
    if (ok) {
      ++it;
      continue;
    }
    if (auto skip = unreadable(ok.error().message); !skip) return tl::unexpected(skip.error());
    it = slices.erase(it);
  }
  if (slices.empty()) return error("no slice of series " + seriesLabel(chosen) + " can be read");

  LoadedImage loaded;
  {
    std::string note = "chose series " + seriesLabel(chosen) + " (" + std::to_string(slices.size()) +
                       (slices.size() == 1 ? " slice)" : " slices)");
    if (series.size() > 1) {
      std::size_t otherFiles = 0;
      for (const auto& [uid, other] : series)
        if (uid != chosen) otherFiles += other.size();
      note += "; skipped " + std::to_string(series.size() - 1) + " other series (" + std::to_string(otherFiles) +
              " files)";
    }
    if (notImages) note += "; ignored " + std::to_string(notImages) + " DICOM files without images";
    loaded.notes.push_back(note);
    if (!skipped.empty()) {
      std::string list;
      for (std::size_t i = 0; i < skipped.size() && i < 5; ++i) list += (i ? "; " : "") + skipped[i];
      if (skipped.size() > 5) list += "; and " + std::to_string(skipped.size() - 5) + " more";
      loaded.notes.push_back("skipped " + std::to_string(skipped.size()) + " unreadable file" +
                             (skipped.size() == 1 ? "" : "s") + ": " + list);
    }
  }

  // Consistency across the series (each slice's own header was checked as it was read).
  const SliceHeader& ref = slices.front();
  {
    std::map<std::pair<int, int>, std::vector<std::string>> sizes;
    for (const SliceHeader& h : slices) sizes[{h.columns, h.rows}].push_back(h.name);
    if (sizes.size() > 1) {
      std::string list;
      for (const auto& [size, names] : sizes)
        list += (list.empty() ? "" : ", ") + std::to_string(size.first) + "x" + std::to_string(size.second) + " (" +
                (names.size() == 1 ? names.front() : std::to_string(names.size()) + " files") + ")";
      return error("mixed slice sizes in one series: " + list);
    }
  }
  const auto& o = *ref.orientation;
  const Vec3 row{o[0], o[1], o[2]}, column{o[3], o[4], o[5]};
  if (auto ok = dicom::checkOrientation(row, column); !ok) return error(ref.name + ": " + ok.error().message);
  for (const SliceHeader& h : slices) {
    for (int i = 0; i < 6; ++i)
      if (std::abs((*h.orientation)[i] - o[i]) > 1e-3)
        return error("slices have different orientations (" + h.name + " differs from " + ref.name + ")");
    for (int i = 0; i < 2; ++i)
      if (std::abs((*h.pixelSpacing)[i] - (*ref.pixelSpacing)[i]) > 1e-4 * (*ref.pixelSpacing)[i])
        return error("slices have different PixelSpacing (" + h.name + " differs from " + ref.name + ")");
    if (h.bitsAllocated != ref.bitsAllocated || h.pixelRepresentation != ref.pixelRepresentation)
      return error("slices store pixels differently (" + h.name + " differs from " + ref.name + ")");
  }

  dicom::StackInput stackInput;
  stackInput.row = (1.0 / norm(row)) * row;
  stackInput.column = (1.0 / norm(column)) * column;
  stackInput.nominalSpacingMm = ref.spacingBetweenSlices > 0 ? ref.spacingBetweenSlices : ref.sliceThickness;
  for (const SliceHeader& h : slices) {
    stackInput.positionsMm.push_back({(*h.position)[0], (*h.position)[1], (*h.position)[2]});
    stackInput.names.push_back(h.name);
  }
  auto stack = dicom::stackSlices(stackInput);
  if (!stack) return error(stack.error().message);

  Geometry geometry;
  geometry.dims = {ref.columns, ref.rows, stack->sliceCount};
  // PixelSpacing is (between rows, between columns): i runs along a row, so its spacing is the second.
  geometry.spacingMm = {(*ref.pixelSpacing)[1], (*ref.pixelSpacing)[0], stack->spacingMm};
  geometry.originMm = stack->originMm;
  for (int r = 0; r < 3; ++r) {
    geometry.direction.m[r][0] = stackInput.row[r];
    geometry.direction.m[r][1] = stackInput.column[r];
    geometry.direction.m[r][2] = stack->normal[r];
  }
  if (slices.size() == 1)
    loaded.notes.push_back("single slice: thickness " + formatNumber(stack->spacingMm) + " mm taken from " +
                           (ref.spacingBetweenSlices > 0 ? "SpacingBetweenSlices"
                            : ref.sliceThickness > 0    ? "SliceThickness"
                                                        : "a default"));
  else if (ref.sliceThickness > 0 && std::abs(ref.sliceThickness - stack->spacingMm) > 0.01)
    loaded.notes.push_back("slice spacing " + formatNumber(stack->spacingMm) +
                           " mm from ImagePositionPatient (SliceThickness says " + formatNumber(ref.sliceThickness) +
                           " mm)");

  // Each decoding thread holds one slice at a time: DCMTK's copy of the stored pixels, the decoded
  // frame, and for JPEG 2000 the codestream and OpenJPEG's 32-bit samples.
  const unsigned threads = std::clamp(std::thread::hardware_concurrency(), 1u, 8u);
  const std::size_t workers = std::min<std::size_t>(threads, slices.size());
  std::uint64_t largestFile = 0;
  for (const SliceHeader& h : slices) largestFile = std::max(largestFile, h.fileBytes);
  const double sliceBytes = double(ref.columns) * double(ref.rows) * (2.0 * (ref.bitsAllocated / 8) + 8.0) + double(largestFile);
  if (auto fits = detail::checkImageFits(folder, geometry.dims, double(workers) * sliceBytes, options); !fits)
    return tl::unexpected(fits.error());

  loaded.image = FloatVolume(geometry);
  loaded.storedKind = storedKindOf(ref);
  loaded.modality = ref.modality;
  loaded.rescaleGiven = ref.rescaleGiven;

  // Decode slices in parallel: each worker owns its DCMTK file objects and OpenJPEG codecs.
  const std::size_t sliceVoxels = std::size_t(ref.columns) * std::size_t(ref.rows);
  std::mutex mutex;  // guards firstError, decoded and the progress callback
  std::optional<std::pair<std::size_t, Error>> firstError;
  std::size_t decoded = 0;
  if (options.progress) options.progress(0, slices.size());
  forEachRowInParallel(
      int(slices.size()),
      [&](int row) {
        if (detail::loadCancelled(options)) return;
        const std::size_t s = std::size_t(row);
        float* out = loaded.image.voxels.data() + std::size_t(stack->sliceOf[s]) * sliceVoxels;
        auto ok = readSlicePixels(slices[s], out);
        std::lock_guard lock(mutex);
        if (!ok && (!firstError || s < firstError->first)) firstError = {s, ok.error()};
        if (ok && options.progress) options.progress(++decoded, slices.size());
      },
      int(workers));
  if (detail::loadCancelled(options)) return tl::unexpected(detail::cancelledError(folder));
  if (firstError) return error(firstError->second.message);
  return loaded;
}

}  // namespace

Result<LoadedImage> loadDicomSeries(const std::string& folder, const ImageLoadOptions& options) {
  return withPrintableError(readDicomSeries(folder, options));
}

}  // namespace at
