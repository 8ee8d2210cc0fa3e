// Conversions from loaded float images to HU volumes and label maps, label-name JSON, and the
// memory budget loaders check before allocating.
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "volume/image_file.h"

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
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail(ErrorKind::Io, path + ": cannot open the label names file");
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    return fail(path + ": not valid JSON (" + what + ")");
  }
  if (!json.is_object())
    return fail(path + ": expected a JSON object { \"label value\": \"name\", … }");
  std::map<std::uint16_t, std::string> names;
  for (const auto& [key, value] : json.items()) {
    std::size_t used = 0;
    unsigned long label = 0;
    bool ok = !key.empty() && key.find_first_not_of("0123456789") == std::string::npos;
    if (ok) {
      try {
        label = std::stoul(key, &used);
      } catch (const std::exception&) {
        ok = false;
      }
    }
    if (!ok || used != key.size() || label > 65535)
      return fail(path + ": key \"" + key + "\" is not a label value 0..65535");
    if (!value.is_string()) return fail(path + ": the name of label " + key + " is not a string");
    names[std::uint16_t(label)] = value.get<std::string>();
  }
  return names;
}

std::size_t availableImageBytes() {
  // Half of MemAvailable: the image is usually held twice for a while (file data and floats), and
  // the rest of the app needs room too.
  constexpr std::size_t kFallback = std::size_t(2) << 30;
  std::ifstream meminfo("/proc/meminfo");
  std::string key;
  while (meminfo >> key) {
    if (key == "MemAvailable:") {
      unsigned long long kib = 0;
      if (meminfo >> kib) return std::size_t(kib) * 1024 / 2;
      break;
    }
    meminfo.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return kFallback;
}

}  // namespace at
