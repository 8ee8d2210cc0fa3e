// openDatasetFiles: a volume, optional labels and optional names → a Dataset on the volume's grid.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "core/strings.h"
#include "core/printable_text.h"
#include "dicom_support.h"
#include "volume/dataset_source.h"
#include "volume/label_fit.h"
#include "volume/image_file.h"
#include "volume/resample.h"

namespace fs = std::filesystem;

namespace at {

namespace {

using dicom::formatNumber;

// The box spanned by a grid's voxel centres in LPS millimetres.
struct BoxMm {
  Vec3 lo{0, 0, 0}, hi{0, 0, 0};
};

BoxMm boxOf(const Geometry& g) {
  BoxMm box;
  bool first = true;
  for (int c = 0; c < 8; ++c) {
    const Vec3 ijk{(c & 1) ? g.dims.x - 1.0 : 0.0, (c & 2) ? g.dims.y - 1.0 : 0.0, (c & 4) ? g.dims.z - 1.0 : 0.0};
    const Vec3 p = g.indexToPatient(ijk);
    for (int a = 0; a < 3; ++a) {
      box.lo[a] = first ? p[a] : std::min(box.lo[a], p[a]);
      box.hi[a] = first ? p[a] : std::max(box.hi[a], p[a]);
    }
    first = false;
  }
  return box;
}

std::string describe(const BoxMm& box) {
  static const char* const axes[3] = {"x ", ", y ", ", z "};
  std::string out;
  for (int a = 0; a < 3; ++a) {
    out += axes[a];
    out += formatNumber(box.lo[a]);
    out += "…";
    out += formatNumber(box.hi[a]);
  }
  return out + " mm";
}

bool boxesOverlap(const Geometry& a, const Geometry& b) {
  // Half a voxel of slack around each box: the grids' voxels, not just their centres, count.
  const BoxMm ba = boxOf(a), bb = boxOf(b);
  for (int axis = 0; axis < 3; ++axis) {
    const double slack = 0.5 * std::max({a.spacingMm[0], a.spacingMm[1], a.spacingMm[2], b.spacingMm[0],
                                         b.spacingMm[1], b.spacingMm[2]});
    if (ba.hi[axis] + slack < bb.lo[axis] || bb.hi[axis] + slack < ba.lo[axis]) return false;
  }
  return true;
}

std::string datasetIdFromPath(const std::string& path) {
  fs::path p(path);
  if (p.filename().empty()) p = p.parent_path();  // "ct/" → "ct"
  std::string name = p.filename().string();
  for (const char* suffix : {".nii.gz", ".nii", ".nrrd", ".nhdr", ".inv3", ".dcm"}) {
    const std::string s = suffix;
    if (name.size() > s.size() && name.compare(name.size() - s.size(), s.size(), s) == 0) {
      name.resize(name.size() - s.size());
      break;
    }
  }
  const std::string id = str::identifier(name);
  return id.empty() ? "dataset" : id;
}

// A label's name from the label file's own segments, else from the names file; empty if neither has one.
std::string labelNameFrom(std::uint16_t label, const std::vector<SegmentInfo>& segments,
                          const std::map<std::uint16_t, std::string>& names) {
  auto segment = std::find_if(segments.begin(), segments.end(), [&](const SegmentInfo& i) { return i.label == label; });
  if (segment != segments.end()) return segment->name;
  if (auto it = names.find(label); it != names.end()) return it->second;
  return {};
}

// One line naming the labels file and every label the resampling lost (at most 8, then a count),
// each with its name from the file's segments or the names file where it has one.
std::string lostLabelsWarning(const std::vector<LostLabel>& lost, const std::vector<SegmentInfo>& segments,
                              const std::map<std::uint16_t, std::string>& names, const std::string& labelsPath,
                              const Geometry& grid) {
  constexpr std::size_t kNamed = 8;
  std::string listed;
  for (std::size_t n = 0; n < lost.size() && n < kNamed; ++n) {
    const LostLabel& l = lost[n];
    const std::string name = labelNameFrom(l.label, segments, names);
    if (n) listed += ", ";
    listed += std::to_string(l.label);
    if (!name.empty()) listed += " '" + printableText(name, 60) + "'";
    listed += " (" + str::countOf(static_cast<long long>(l.sourceVoxels), "voxel") + ")";
  }
  if (lost.size() > kNamed) listed += " and " + std::to_string(lost.size() - kNamed) + " more";
  const std::string spacing = formatNumber(grid.spacingMm[0]) + " x " + formatNumber(grid.spacingMm[1]) + " x " +
                              formatNumber(grid.spacingMm[2]) + " mm";
  return labelsPath + ": " + str::countOf(static_cast<long long>(lost.size()), "label") + " lost every voxel when resampled onto the volume's " +
         spacing + " grid (smaller than its voxels, or outside the volume), so " +
         (lost.size() == 1 ? "it is" : "they are") + " left out: " + listed +
         " - label on the volume's own grid to keep them";
}

}  // namespace

Result<Dataset> openDatasetFiles(const DatasetFiles& files, const DatasetLoadControl& control) {
  if (files.volumePath.empty()) return fail("no volume file given");
  const auto cancelled = [&] { return control.cancel && control.cancel->load(std::memory_order_relaxed); };
  // The loader options of one part: its progress goes to control.progress under that part.
  const auto optionsFor = [&](DatasetLoadPart part) {
    ImageLoadOptions options;
    options.cancel = control.cancel;
    options.skipUnreadableFiles = files.skipUnreadableFiles;
    options.dataFolder = files.dataFolder;
    if (control.progress) {
      control.progress(part, 0, 0);
      options.progress = [&control, part](std::size_t done, std::size_t total) { control.progress(part, done, total); };
    }
    return options;
  };
  ImageLoadOptions volumeOptions = optionsFor(DatasetLoadPart::Volume);
  volumeOptions.dicomSeriesUid = files.dicomSeriesUid;
  auto volumeImage = loadImageFile(files.volumePath, volumeOptions);
  if (!volumeImage) return tl::unexpected(volumeImage.error());
  if (auto ok = takeGivenModality(*volumeImage, files.modality, files.volumePath); !ok) return tl::unexpected(ok.error());
  auto volume = toStoredVolume(*volumeImage, files.volumePath, files.intensity);
  if (!volume) return tl::unexpected(volume.error());

  Dataset dataset;
  dataset.id = files.id.empty() ? datasetIdFromPath(files.volumePath) : files.id;
  dataset.displayName = dataset.id;
  dataset.volume = std::move(volume->volume);
  dataset.intensity = std::move(volume->intensity);
  if (files.intercept || files.slope)
    if (auto ok = applyRescale(dataset.volume, dataset.intensity, files.intercept.value_or(0), files.slope.value_or(1),
                               files.intensity);
        !ok)
      return fail(files.volumePath + ": " + ok.error().message);
  dataset.provenance.source = files.volumePath;
  dataset.provenance.notes = volumeImage->notes;
  const Geometry& grid = dataset.volume.geometry;

  std::vector<SegmentInfo> segments;
  std::vector<LostLabel> lostLabels;  // labels the resampling onto the volume's grid left without a voxel
  if (files.labelsPath.empty()) {
    dataset.labels = LabelMap(grid, 0);
  } else {
    if (cancelled()) return fail(files.labelsPath + ": loading cancelled");
    auto labelImage = loadImageFile(files.labelsPath, optionsFor(DatasetLoadPart::Labels));
    if (!labelImage) return tl::unexpected(labelImage.error());
    auto labels = toLabelMap(*labelImage, files.labelsPath);
    if (!labels) return tl::unexpected(labels.error());
    for (const std::string& note : labelImage->notes) dataset.provenance.notes.push_back(files.labelsPath + ": " + note);
    segments = labelImage->segments;
    dataset.provenance.labelsSource = files.labelsPath;

    if (labels->geometry.sameGridAs(grid)) {
      labels->geometry = grid;
      dataset.labels = std::move(*labels);
    } else {
      if (!boxesOverlap(labels->geometry, grid))
        return fail(files.labelsPath + " does not overlap " + files.volumePath + " on the patient frame: labels span " +
                    describe(boxOf(labels->geometry)) + ", the volume spans " + describe(boxOf(grid)));
      if (cancelled()) return fail(files.labelsPath + ": loading cancelled");
      if (control.progress) control.progress(DatasetLoadPart::Resampling, 0, 0);
      auto resampled = resampleLabelsNearest(*labels, grid);
      if (!resampled)
        return fail(files.labelsPath + " cannot be resampled onto " + files.volumePath + ": " +
                    resampled.error().message);
      dataset.provenance.notes.push_back(
          "labels resampled (nearest neighbour) from their " + labels->geometry.dims.toString() + " " +
          labels->geometry.orientationCode() + " grid onto the volume's " + grid.dims.toString() + " " +
          grid.orientationCode() + " grid through both patient frames");
      lostLabels = labelsLostInResampling(*labels, *resampled);
      dataset.labels = std::move(*resampled);
    }
    if (auto warning = labelFitWarning(dataset.volume, dataset.intensity, dataset.labels, files.labelsPath); !warning.empty())
      dataset.provenance.warnings.push_back(warning);
  }

  if (cancelled()) return fail((files.labelsPath.empty() ? files.volumePath : files.labelsPath) + ": loading cancelled");
  std::map<std::uint16_t, std::string> names;
  if (!files.namesPath.empty()) {
    if (control.progress) control.progress(DatasetLoadPart::Names, 0, 0);
    auto loadedNames = loadLabelNames(files.namesPath);
    if (!loadedNames) return tl::unexpected(loadedNames.error());
    names = std::move(*loadedNames);
  }
  if (!lostLabels.empty())
    dataset.provenance.warnings.push_back(lostLabelsWarning(lostLabels, segments, names, files.labelsPath, grid));

  // Only labels present in the map become structures.
  std::vector<std::size_t> counts(65536, 0);
  for (std::uint16_t v : dataset.labels.voxels) ++counts[v];
  std::set<std::string> usedIds;
  for (std::size_t label = 1; label < counts.size(); ++label) {
    if (!counts[label]) continue;
    Structure s;
    s.label = std::uint16_t(label);
    s.colour = paletteColour(s.label);
    const std::string name = labelNameFrom(s.label, segments, names);
    auto segment = std::find_if(segments.begin(), segments.end(), [&](const SegmentInfo& i) { return i.label == label; });
    if (segment != segments.end()) s.colour = segment->colour;
    s.id = str::identifier(name);
    if (s.id.empty()) s.id = "label_" + std::to_string(label);
    if (usedIds.count(s.id)) s.id.append(1, '_').append(std::to_string(label));
    usedIds.insert(s.id);
    // Names come from the files: no line break or terminal escape may reach a listing or a message.
    s.displayName = name.empty() ? "Label " + std::to_string(label) : displayNameOf(printableText(name, 120));
    dataset.structures.push_back(std::move(s));
  }
  return dataset;
}

}  // namespace at
