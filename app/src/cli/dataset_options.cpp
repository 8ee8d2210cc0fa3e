#include "dataset_options.h"

#include <cstdio>
#include <filesystem>

#include "intensity_notes.h"
#include "printable_output.h"

namespace at::app {

namespace fs = std::filesystem;

std::set<std::string> withDatasetOptions(std::set<std::string> commandOptions) {
  commandOptions.insert({"labels", "names", "series", "intensity", "nrrd-data", "intercept", "slope", "modality"});
  return commandOptions;
}

std::set<std::string> withDatasetFlags(std::set<std::string> commandFlags) {
  commandFlags.insert("skip-unreadable");
  return commandFlags;
}

DatasetRequest datasetRequestFrom(const cli::Args& args, const std::string& name) {
  DatasetRequest request;
  request.name = name;
  request.labelsPath = args.valueOr("labels", "");
  request.namesPath = args.valueOr("names", "");
  request.seriesUid = args.valueOr("series", "");
  request.intensity = args.valueOr("intensity", "");
  request.dbPath = args.db();
  request.skipUnreadableFiles = args.has("skip-unreadable");
  if (auto folder = args.value("nrrd-data")) request.dataFolder = fs::absolute(*folder).string();
  request.intercept = args.valueOr("intercept", "");
  request.slope = args.valueOr("slope", "");
  request.modality = args.valueOr("modality", "");
  return request;
}

void reportDatasetWarnings(const Dataset& dataset) {
  for (const std::string& warning : dataset.provenance.warnings)
    terminalFprintf(stderr, "anatomy-tutor: warning: %s\n", warning.c_str());
}

void applyDatasetWindow(const Dataset& dataset, float& windowMin, float& windowMax, bool windowGiven,
                        bool densityWeights) {
  const IntensityModel& m = dataset.intensity;
  if (!m.hounsfield() && !windowGiven) {
    windowMin = m.window[0];
    windowMax = m.window[1];
  }
  static bool noted = false;
  if (!densityWeights || noted) return;
  if (const auto note = densityWeightsNote(dataset)) {
    noted = true;
    terminalFprintf(stderr, "anatomy-tutor: note: %s\n", note->c_str());
  }
}

}  // namespace at::app
