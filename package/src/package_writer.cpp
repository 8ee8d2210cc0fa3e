// Writing a course package: the documents are made in memory, the data files hashed from disk,
// the manifest written first, then every entry in a fixed order with fixed metadata.
#include <archive.h>
#include <archive_entry.h>

#include <algorithm>
#include <fstream>
#include <vector>

#include "archive_handles.h"
#include "core/atomic_file.h"
#include "core/sha256.h"
#include "lessons/course_json.h"
#include "package/course_package.h"
#include "volume/nrrd_io.h"
#include "volume/structure_forms.h"

namespace at::package {

namespace {

namespace fs = std::filesystem;

struct Entry {
  std::string path;
  std::string text;        // a document; empty for a data file
  fs::path file;           // a data file
  std::uint64_t size = 0;
  std::string sha256;
};

Status hashFile(const fs::path& file, Entry& entry) {
  if (auto ok = checkRegularFile(file.string(), file.string()); !ok) return ok;
  std::ifstream in(file, std::ios::binary);
  if (!in) return fail(ErrorKind::Io, file.string() + ": cannot read");
  Sha256 sha;
  std::vector<char> buffer(std::size_t(1) << 20);
  std::uint64_t size = 0;
  while (in) {
    in.read(buffer.data(), std::streamsize(buffer.size()));
    const auto got = in.gcount();
    if (got > 0) {
      sha.update(reinterpret_cast<const unsigned char*>(buffer.data()), std::size_t(got));
      size += std::uint64_t(got);
    }
  }
  if (in.bad()) return fail(ErrorKind::Io, file.string() + ": read error");
  entry.size = size;
  entry.sha256 = sha.hex();
  return {};
}

Entry document(std::string path, std::string text) {
  Entry e;
  e.path = std::move(path);
  e.text = std::move(text);
  e.size = e.text.size();
  e.sha256 = sha256Hex(e.text);
  return e;
}

// One entry: a regular file, mode 0644, owned by 0:0, dated at the epoch (reproducible bytes).
Status writeEntry(archive* a, const Entry& e, const std::string& out) {
  std::unique_ptr<archive_entry, void (*)(archive_entry*)> header(archive_entry_new(), archive_entry_free);
  if (!header) return fail(ErrorKind::Io, out + ": out of memory");
  archive_entry_set_pathname(header.get(), e.path.c_str());
  archive_entry_set_filetype(header.get(), AE_IFREG);
  archive_entry_set_perm(header.get(), 0644);
  archive_entry_set_size(header.get(), la_int64_t(e.size));
  archive_entry_set_mtime(header.get(), 0, 0);
  if (archive_write_header(a, header.get()) != ARCHIVE_OK)
    return fail(ErrorKind::Io, out + ": " + e.path + ": " + archiveMessage(a));
  const auto put = [&](const char* data, std::size_t n) -> Status {
    if (archive_write_data(a, data, n) != la_ssize_t(n)) return fail(ErrorKind::Io, out + ": " + e.path + ": " + archiveMessage(a));
    return {};
  };
  if (e.file.empty()) {
    if (auto ok = put(e.text.data(), e.text.size()); !ok) return ok;
  } else {
    std::ifstream in(e.file, std::ios::binary);
    if (!in) return fail(ErrorKind::Io, e.file.string() + ": cannot read");
    std::vector<char> buffer(std::size_t(1) << 20);
    std::uint64_t written = 0;
    while (in) {
      in.read(buffer.data(), std::streamsize(buffer.size()));
      const auto got = in.gcount();
      if (got <= 0) break;
      if (auto ok = put(buffer.data(), std::size_t(got)); !ok) return ok;
      written += std::uint64_t(got);
    }
    if (written != e.size) return fail(ErrorKind::Io, e.file.string() + ": changed while the package was written");
  }
  return {};
}

Status checkInput(const PackageInput& in) {
  const DatasetEntry& d = in.dataset;
  if (d.name != in.course.datasetId)
    return fail("package: the dataset entry '" + d.name + "' is not the course's dataset '" + in.course.datasetId + "'");
  const bool builtin = d.source == VolumeSource::Builtin;
  if (builtin && (!in.structures.empty() || !in.labelsFile.empty() || !in.volumeFile.empty()))
    return fail("package: a built-in dataset's package carries no structures, labels or volume");
  if (!builtin && (in.structures.empty() || !d.geometry || d.sourceVolumeChecksum.empty()))
    return fail("package: dataset '" + d.name + "' needs its structures, geometry and volume checksum");
  if ((d.source == VolumeSource::Included) == in.volumeFile.empty())
    return fail(std::string("package: the volume file ") + (in.volumeFile.empty() ? "is missing" : "is given but not included"));
  if (d.source == VolumeSource::Reference && d.referenceFileName.empty())
    return fail("package: a referenced volume needs the file's name");
  // Nothing the reader would refuse: the species and structures held to the importers' forms.
  if (!isValidSpecies(d.species)) return fail("package: species '" + d.species + "' is not a species name (lower-case letters, '-', '_')");
  if (!in.structures.empty())
    if (auto ok = parseStructuresJson(structuresToJson(in.structures), "package: dataset/structures.json"); !ok)
      return tl::unexpected(ok.error());
  for (const PackagedPreset& p : in.presets)
    if (!safeEntryName(p.id) || p.id.find('/') != std::string::npos)
      return fail("package: preset id '" + p.id + "' is not a plain file name");
  return {};
}

}  // namespace

Status writePackage(const fs::path& out, const PackageInput& input) {
  if (auto ok = checkInput(input); !ok) return ok;
  std::vector<Entry> entries;
  entries.push_back(document("course.json", lessons::courseToJson(input.course) + "\n"));
  std::vector<PackagedPreset> presets = input.presets;
  std::sort(presets.begin(), presets.end(), [](const auto& a, const auto& b) { return a.id < b.id; });
  for (std::size_t i = 1; i < presets.size(); ++i)
    if (presets[i].id == presets[i - 1].id) return fail("package: preset '" + presets[i].id + "' is given twice");
  for (const PackagedPreset& p : presets)
    entries.push_back(document("presets/" + p.id + ".json", p.json.empty() ? render::presetToJson(p.preset) : p.json));
  if (!input.structures.empty()) entries.push_back(document("dataset/structures.json", structuresToJson(input.structures)));
  for (const auto& [path, file] : {std::pair{"dataset/labels.nrrd", input.labelsFile}, std::pair{"dataset/volume.nrrd", input.volumeFile}}) {
    if (file.empty()) continue;
    Entry e;
    e.path = path;
    e.file = file;
    if (auto ok = hashFile(file, e); !ok) return ok;
    entries.push_back(std::move(e));
  }

  Manifest manifest;
  manifest.createdBy = input.createdBy;
  manifest.courseId = input.course.id;
  manifest.courseVersion = input.course.version;
  manifest.courseTitle = input.course.title;
  manifest.dataset = input.dataset;
  // Version 1 readers know every field but the reading: a package without one stays readable by them.
  manifest.formatVersion = input.dataset.reading ? kFormatVersion : 1;
  for (const Entry& e : entries) manifest.files.push_back({e.path, e.size, e.sha256});
  entries.insert(entries.begin(), document("manifest.json", manifestToJson(manifest)));

  // libarchive writes into an AtomicFile: the old package stays until the new one is complete.
  auto file = AtomicFile::create(out.string());
  if (!file) return tl::unexpected(file.error());
  struct Sink {
    AtomicFile* file;
    Status status;
  } sink{&*file, {}};
  const auto writeBlock = [](archive*, void* data, const void* buffer, size_t length) -> la_ssize_t {
    auto* s = static_cast<Sink*>(data);
    s->status = s->file->write(std::string_view(static_cast<const char*>(buffer), length));
    return s->status ? la_ssize_t(length) : la_ssize_t(-1);
  };
  ArchiveWriter a(archive_write_new());
  if (!a) return fail(ErrorKind::Io, out.string() + ": out of memory");
  archive_write_set_format_pax_restricted(a.get());
  if (archive_write_open(a.get(), &sink, nullptr, writeBlock, nullptr) != ARCHIVE_OK)
    return fail(ErrorKind::Io, out.string() + ": cannot create (" + archiveMessage(a.get()) + ")");
  for (const Entry& e : entries)
    if (auto ok = writeEntry(a.get(), e, out.string()); !ok) return sink.status ? ok : sink.status;
  const bool closed = archive_write_close(a.get()) == ARCHIVE_OK;
  if (!sink.status) return sink.status;
  if (!closed) return fail(ErrorKind::Io, out.string() + ": " + archiveMessage(a.get()));
  a.reset();
  return file->commit();
}

Result<DatasetFilesWritten> writeDatasetFiles(const Dataset& dataset, const fs::path& dir, bool withLabels) {
  DatasetFilesWritten out;
  out.volume = dir / "volume.nrrd";
  FloatVolume volume;
  volume.geometry = dataset.volume.geometry;
  volume.voxels.assign(dataset.volume.voxels.begin(), dataset.volume.voxels.end());
  if (auto ok = writeNrrd(out.volume.string(), volume, ScalarKind::Int16); !ok) return tl::unexpected(ok.error());
  if (withLabels) {
    out.labels = dir / "labels.nrrd";
    FloatVolume labels;
    labels.geometry = dataset.labels.geometry;
    labels.voxels.assign(dataset.labels.voxels.begin(), dataset.labels.voxels.end());
    if (auto ok = writeNrrd(out.labels.string(), labels, ScalarKind::UInt16); !ok) return tl::unexpected(ok.error());
  }
  return out;
}

std::optional<VolumeReading> includedVolumeReading(const Dataset& dataset) {
  const IntensityModel& model = dataset.intensity;
  // An MR's modality would be lost with the DICOM header, and with it the note that its intensities
  // are not attenuation; the others (CT, none) change nothing a student sees.
  const bool modalityMatters = !model.attenuationLike();
  // What the importer's loader knows of volume.nrrd: int16 values, no rescale, and no modality but
  // the one this reading records (which counts in its unit as a file's own: DatasetFiles::modality).
  IntensityEvidence evidence;
  if (modalityMatters) evidence.modality = model.modality;
  if (!dataset.volume.voxels.empty()) {
    const auto [lo, hi] = std::minmax_element(dataset.volume.voxels.begin(), dataset.volume.voxels.end());
    evidence.minValue = *lo;
    evidence.maxValue = *hi;
  }
  const bool asStored = model.slope == 1 && model.intercept == 0;
  const bool sameValues = decideIntensity(evidence, IntensityChoice::Auto).first == model.unit && asStored;
  if (sameValues && !modalityMatters) return std::nullopt;
  VolumeReading reading;
  if (!sameValues) {
    reading.intensity = model.hounsfield() ? IntensityChoice::Hounsfield : IntensityChoice::Plain;
    if (model.intercept != 0) reading.intercept = model.intercept;
    if (model.slope != 1) reading.slope = model.slope;
  }
  if (modalityMatters) reading.modality = model.modality;
  return reading;
}

}  // namespace at::package
