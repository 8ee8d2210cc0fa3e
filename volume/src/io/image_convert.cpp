// Conversions from loaded float images to HU volumes and label maps, label-name JSON, and the
// memory budget loaders check before allocating.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <cstdint>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "volume/image_file.h"
#include "core/json_document.h"
#include "core/printable_text.h"
#include "volume/intensity_landmarks.h"

namespace at {

const char* toString(ScalarKind kind) {
  switch (kind) {
    case ScalarKind::Int8: return "int8";
    case ScalarKind::UInt8: return "uint8";
    case ScalarKind::Int16: return "int16";
    case ScalarKind::UInt16: return "uint16";
    case ScalarKind::Int32: return "int32";
    case ScalarKind::UInt32: return "uint32";
    case ScalarKind::Float32: return "float32";
    case ScalarKind::Float64: return "float64";
  }
  return "unknown";
}

namespace {

// Soft tissue lies within this many HU of water (fat −100, muscle and organs up to about 100).
constexpr double kSoftTissueHu = 150;

std::string voxelName(const Dims& dims, std::size_t index) {
  const std::size_t i = index % std::size_t(dims.x);
  const std::size_t j = (index / std::size_t(dims.x)) % std::size_t(dims.y);
  const std::size_t k = index / (std::size_t(dims.x) * std::size_t(dims.y));
  return "voxel (" + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) + ")";
}

std::string valueText(float v) {
  if (std::isnan(v)) return "NaN";
  if (std::isinf(v)) return v > 0 ? "+inf" : "-inf";
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

Result<Volume> toHuVolume(const LoadedImage& loaded, const std::string& pathForMessages) {
  const FloatVolume& image = loaded.image;
  Volume out;
  out.geometry = image.geometry;
  out.voxels.resize(image.voxels.size());
  for (std::size_t n = 0; n < image.voxels.size(); ++n) {
    const float v = image.voxels[n];
    if (!std::isfinite(v))
      return fail(pathForMessages + ": " + voxelName(image.dims(), n) + " is " + valueText(v) +
                  "; a CT volume needs finite Hounsfield units");
    const double r = std::nearbyint(double(v));
    if (r < std::numeric_limits<std::int16_t>::min() || r > std::numeric_limits<std::int16_t>::max())
      return fail(pathForMessages + ": " + voxelName(image.dims(), n) + " is " + valueText(v) +
                  ", outside the int16 range of Hounsfield units");
    out.voxels[n] = std::int16_t(r);
  }
  return out;
}

Status takeGivenModality(LoadedImage& loaded, const std::string& given, const std::string& pathForMessages) {
  if (given.empty() || loaded.modality == given) return {};
  if (!loaded.modality.empty())
    return fail(pathForMessages + ": its DICOM Modality is " + loaded.modality + ", not the " + given +
                " given (a modality is given only for files that record none)");
  loaded.modality = given;
  loaded.notes.push_back("modality " + given + " as given (the file records none)");
  return {};
}

Result<StoredVolume> toStoredVolume(const LoadedImage& loaded, const std::string& pathForMessages,
                                    IntensityChoice choice) {
  const FloatVolume& image = loaded.image;
  IntensityEvidence evidence;
  evidence.modality = loaded.modality;
  evidence.rescaleGiven = loaded.rescaleGiven;
  evidence.unsignedStorage = loaded.storedKind == ScalarKind::UInt8 || loaded.storedKind == ScalarKind::UInt16 ||
                             loaded.storedKind == ScalarKind::UInt32;
  bool integers = true, first = true;
  for (std::size_t n = 0; n < image.voxels.size(); ++n) {
    const float v = image.voxels[n];
    if (!std::isfinite(v))
      return fail(pathForMessages + ": " + voxelName(image.dims(), n) + " is " + valueText(v) +
                  "; a volume needs finite values");
    if (first || v < evidence.minValue) evidence.minValue = v;
    if (first || v > evidence.maxValue) evidence.maxValue = v;
    first = false;
    integers = integers && v == std::floor(v);
  }
  StoredVolume out;
  IntensityModel& model = out.intensity;
  auto [unit, reason] = decideIntensity(evidence, choice);
  model.unit = unit;
  model.reason = reason;
  model.modality = loaded.modality;
  if (model.hounsfield()) {
    auto hu = toHuVolume(loaded, pathForMessages);
    if (!hu) return tl::unexpected(hu.error());
    out.volume = std::move(*hu);
    return out;
  }
  // Plain intensities: as they are where they fit; shifted by a whole number into int16 where
  // integers span at most 65536 values; scaled otherwise.
  constexpr double kLow = std::numeric_limits<std::int16_t>::min(), kHigh = std::numeric_limits<std::int16_t>::max();
  const double lo = evidence.minValue, hi = evidence.maxValue;
  if (integers && lo >= kLow && hi <= kHigh) {
    model.intercept = 0;
  } else if (integers && hi - lo <= kHigh - kLow) {
    model.intercept = lo - kLow;
  } else {
    model.slope = hi > lo ? (hi - lo) / (kHigh - kLow) : 1.0;
    model.intercept = lo - kLow * model.slope;
  }
  out.volume.geometry = image.geometry;
  out.volume.voxels.resize(image.voxels.size());
  for (std::size_t n = 0; n < image.voxels.size(); ++n) {
    const double s = std::nearbyint((double(image.voxels[n]) - model.intercept) / model.slope);
    out.volume.voxels[n] = std::int16_t(std::clamp(s, kLow, kHigh));
  }
  model.window = histogramWindow(out.volume.voxels);
  // A CT stored without its rescale (HU + 1024: air near 0, soft tissue near 1024, as VTK's headsq)
  // reads as plain intensities; the reason says how to read it in HU.
  if (model.modality == "CT" || (model.modality.empty() && !evidence.unsignedStorage)) {
    const SoftTissueLandmarks l = softTissueLandmarks(valueHistogram(out.volume.voxels), int(model.window[0]));
    const double soft = model.valueOf(l.softTissue), air = model.valueOf(model.window[0]);
    if (soft >= 1024 - kSoftTissueHu && soft <= 1024 + kSoftTissueHu && air >= -100 && air <= 300) {
      char hint[200];
      std::snprintf(hint, sizeof hint,
                    "; its air at %.0f and soft tissue at %.0f are where a CT stored as HU + 1024 has them: if it is "
                    "one, --intercept -1024 reads it in HU",
                    air, soft);
      model.reason += hint;
    }
  }
  return out;
}

Result<LabelMap> toLabelMap(const LoadedImage& loaded, const std::string& pathForMessages) {
  const FloatVolume& image = loaded.image;
  LabelMap out;
  out.geometry = image.geometry;
  out.voxels.resize(image.voxels.size());
  for (std::size_t n = 0; n < image.voxels.size(); ++n) {
    const float v = image.voxels[n];
    const char* problem = nullptr;
    if (!std::isfinite(v))
      problem = "not a finite number";
    else if (v < 0)
      problem = "negative";
    else if (v != std::floor(v))
      problem = "not an integer";
    else if (v > 65535.0f)
      problem = "above 65535";
    if (problem)
      return fail(pathForMessages + ": label " + voxelName(image.dims(), n) + " is " + valueText(v) + ", " +
                  problem + "; label values must be integers 0..65535");
    out.voxels[n] = std::uint16_t(v);
  }
  return out;
}

Result<std::map<std::uint16_t, std::string>> loadLabelNames(const std::string& path) {
  // TotalSegmentator's 117 names take 3 KB; anything near this is not a label names file.
  constexpr std::size_t kMaxBytes = std::size_t(16) << 20;
  auto json = readJsonFile(path, path, kMaxBytes);
  if (!json) return tl::unexpected(json.error());
  if (!json->is_object())
    return fail(path + ": expected a JSON object { \"label value\": \"name\", … }");
  std::map<std::uint16_t, std::string> names;
  for (const auto& [key, value] : json->items()) {
    // Digits only, at most 5 of them (65535), so no conversion can overflow.
    const bool digits = !key.empty() && key.size() <= 5 && key.find_first_not_of("0123456789") == std::string::npos;
    const unsigned long label = digits ? std::stoul(key) : 0;
    if (!digits || label > 65535)
      return fail(path + ": key \"" + printableText(key, 40) + "\" is not a label value 0..65535");
    if (!value.is_string()) return fail(path + ": the name of label " + key + " is not a string");
    names[std::uint16_t(label)] = value.get<std::string>();
  }
  return names;
}

namespace {

std::optional<unsigned long long> readNumberFile(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text)) return std::nullopt;
  if (text == "max") return std::numeric_limits<unsigned long long>::max();
  try {
    std::size_t used = 0;
    const unsigned long long value = std::stoull(text, &used);
    if (used != text.size()) return std::nullopt;
    return value;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// "key value" lines (/proc/meminfo "MemAvailable: 123 kB", memory.stat "inactive_file 456").
std::optional<unsigned long long> readKeyedNumber(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::string name;
  while (in >> name) {
    if (name == key) {
      unsigned long long value = 0;
      if (in >> value) return value;
      return std::nullopt;
    }
    in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return std::nullopt;
}

// The memory a cgroup may still take: its limit minus its use without reclaimable file cache,
// the smallest over the cgroup and its ancestors up to `root`. nullopt when nothing is limited.
std::optional<unsigned long long> cgroupHeadroom(const std::filesystem::path& root, const std::string& relative,
                                                 bool v2) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path below = fs::path(relative).relative_path();
  fs::path dir = below.empty() ? root : root / below;
  // Inside a container the path /proc/self/cgroup names may not exist: the namespace's root is ours.
  if (!fs::is_directory(dir, ec)) dir = root;
  const char* limitFile = v2 ? "memory.max" : "memory.limit_in_bytes";
  const char* usageFile = v2 ? "memory.current" : "memory.usage_in_bytes";
  const char* inactiveKey = v2 ? "inactive_file" : "total_inactive_file";
  std::optional<unsigned long long> headroom;
  for (fs::path level = dir;; level = level.parent_path()) {
    const auto limit = readNumberFile((level / limitFile).string());
    // cgroup v1 writes "no limit" as a page-rounded 2^63 − 1.
    if (limit && *limit < (1ull << 62)) {
      unsigned long long used = readNumberFile((level / usageFile).string()).value_or(0);
      const unsigned long long inactive = readKeyedNumber((level / "memory.stat").string(), inactiveKey).value_or(0);
      used = used > inactive ? used - inactive : 0;
      const unsigned long long left = *limit > used ? *limit - used : 0;
      headroom = headroom ? std::min(*headroom, left) : left;
    }
    if (level.string().size() <= root.string().size()) break;  // the hierarchy's root is the last level
  }
  return headroom;
}

}  // namespace

MemoryBudget imageMemoryBudget(const MemoryInfoFiles& files) {
  std::optional<unsigned long long> free;
  std::string source;
  if (const auto kib = readKeyedNumber(files.meminfo, "MemAvailable:")) {
    free = *kib * 1024;
    source = "the machine's available memory";
  }
  // /proc/self/cgroup: "0::/path" (v2) or "4:memory:/path" (v1).
  std::ifstream cgroups(files.selfCgroup);
  std::string line;
  while (std::getline(cgroups, line)) {
    const std::size_t first = line.find(':'), second = line.find(':', first + 1);
    if (first == std::string::npos || second == std::string::npos) continue;
    const std::string controllers = line.substr(first + 1, second - first - 1);
    const std::string relative = line.substr(second + 1);
    std::optional<unsigned long long> headroom;
    if (controllers.empty()) {
      headroom = cgroupHeadroom(files.cgroupRoot, relative, true);
    } else {
      std::istringstream list(controllers);
      std::string controller;
      while (std::getline(list, controller, ','))
        if (controller == "memory") headroom = cgroupHeadroom(std::filesystem::path(files.cgroupRoot) / "memory", relative, false);
    }
    if (headroom && (!free || *headroom < *free)) {
      free = *headroom;
      source = "this process's cgroup memory limit";
    }
  }
  MemoryBudget budget;
  if (!free) {
    budget.bytes = std::size_t(2) << 30;
    budget.source = "2 GiB, as the free memory cannot be read";
    return budget;
  }
  // A quarter stays for the rest of the program (the renderer, the distance fields, the UI).
  budget.bytes = std::size_t(*free / 4 * 3);
  char text[64];
  std::snprintf(text, sizeof text, "%.1f GiB", double(*free) / 1073741824.0);
  budget.source = "3/4 of the " + std::string(text) + " free under " + source;
  return budget;
}

std::size_t availableImageBytes() { return imageMemoryBudget().bytes; }

}  // namespace at
