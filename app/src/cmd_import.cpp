// anatomy-tutor import: registers a dataset (volume + optional labels and names) in the database
// after loading both through openDatasetFiles, which checks that they align.
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <map>

#include "cli_args.h"
#include "commands.h"
#include "db/checksum.h"
#include "db/dataset_store.h"
#include "volume/dataset_source.h"

namespace at::app {

namespace {

constexpr const char* kImportHelp =
    "usage: anatomy-tutor import --volume PATH --name NAME [--labels PATH] [--names NAMES.json]\n"
    "                            [--species SPECIES] [--db PATH]\n\n"
    "Registers a dataset in the database: the volume (a DICOM folder, .nii, .nii.gz, .nrrd or .nhdr),\n"
    "an optional label map on the same anatomy (any of those formats or DICOM SEG) and an optional\n"
    "JSON of label names ({\"1\": \"spleen\", …}). Both are loaded first to check that they align.\n"
    "The database keeps absolute paths, SHA-256 checksums and the geometry, never pixels or patient\n"
    "identifiers. Afterwards the dataset's NAME works wherever a DATASET is asked for.\n\n"
    "  --species  human (default), dog, cat, horse, … (lower-case letters, '-' and '_')\n"
    "  --db       database file (default: $XDG_DATA_HOME/anatomy-tutor/anatomy-tutor.db)\n";

bool validSpecies(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) {
    return std::islower(c) || c == '-' || c == '_';
  });
}

Result<std::string> absolutePath(const std::string& option, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return fail("--" + option + " " + path + ": no such file or folder");
  auto absolute = std::filesystem::weakly_canonical(std::filesystem::absolute(path), ec);
  if (ec) return fail("--" + option + " " + path + ": " + ec.message());
  return absolute.string();
}

}  // namespace

int runImport(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"volume", "labels", "names", "name", "species", "db"}, {});
  if (!args) return reportError("import: " + args.error().message);
  if (args->has("help")) {
    std::printf("%s", kImportHelp);
    return 0;
  }
  if (!args->positional().empty()) return reportError("import: unexpected argument '" + args->positional()[0] + "'");
  const auto volume = args->value("volume");
  const auto name = args->value("name");
  if (!volume) return reportError("import: --volume PATH is required (see --help)");
  if (!name || name->empty()) return reportError("import: --name NAME is required (see --help)");
  if (isBuiltinDatasetName(*name)) return reportError("import: '" + *name + "' is the built-in dataset's name; choose another --name");
  const std::string species = args->valueOr("species", "human");
  if (!validSpecies(species))
    return reportError("import: --species '" + species + "': use lower-case letters, '-' and '_' (human, dog, …)");

  db::DatasetRecord record;
  record.name = *name;
  record.species = species;
  auto volumePath = absolutePath("volume", *volume);
  if (!volumePath) return reportError("import: " + volumePath.error().message);
  record.volumePath = *volumePath;
  if (auto labels = args->value("labels")) {
    auto p = absolutePath("labels", *labels);
    if (!p) return reportError("import: " + p.error().message);
    record.labelsPath = *p;
  }
  if (auto names = args->value("names")) {
    auto p = absolutePath("names", *names);
    if (!p) return reportError("import: " + p.error().message);
    record.namesPath = *p;
  }

  auto database = db::openDatabase(args->value("db"));
  if (!database) return reportError("import: " + database.error().message);
  // Fail fast on a taken name, before the (possibly long) load.
  auto existing = db::findDataset(*database, record.name);
  if (!existing) return reportError("import: " + existing.error().message);
  if (*existing) return reportError("import: a dataset named '" + record.name + "' is already imported; choose another --name");

  auto dataset = openDatasetFiles(db::datasetFiles(record));
  if (!dataset) return reportError("import: " + dataset.error().message);

  // Alignment: every structure must keep voxels on the volume's grid.
  std::map<std::uint16_t, std::size_t> voxels;
  for (std::uint16_t v : dataset->labels.voxels)
    if (v != 0) ++voxels[v];
  if (!record.labelsPath.empty() && voxels.empty())
    return reportError("import: " + record.labelsPath + ": no labelled voxel falls inside the volume " +
                       record.volumePath + " (the two do not overlap in patient space)");
  std::vector<std::string> empty;
  for (const Structure& s : dataset->structures)
    if (voxels.count(s.label) == 0) empty.push_back(s.id);

  auto volumeSum = db::checksumPath(record.volumePath);
  if (!volumeSum) return reportError("import: " + volumeSum.error().message);
  record.volumeChecksum = *volumeSum;
  if (!record.labelsPath.empty()) {
    auto labelsSum = db::checksumPath(record.labelsPath);
    if (!labelsSum) return reportError("import: " + labelsSum.error().message);
    record.labelsChecksum = *labelsSum;
  }
  record.geometry = dataset->volume.geometry;
  record.orientation = record.geometry.orientationCode();

  auto id = db::registerDataset(*database, record, dataset->structures);
  if (!id) return reportError("import: " + id.error().message);

  const Geometry& g = record.geometry;
  std::printf("imported '%s' (%s): %s voxels, spacing %.3g x %.3g x %.3g mm, %s; %zu structures\n",
              record.name.c_str(), record.species.c_str(), g.dims.toString().c_str(), g.spacingMm[0], g.spacingMm[1],
              g.spacingMm[2], record.orientation.c_str(), dataset->structures.size());
  std::printf("  volume  %s  %s\n", record.volumePath.c_str(), record.volumeChecksum.c_str());
  if (!record.labelsPath.empty()) std::printf("  labels  %s  %s\n", record.labelsPath.c_str(), record.labelsChecksum.c_str());
  for (const auto& note : dataset->provenance.notes) std::printf("  note: %s\n", note.c_str());
  if (!empty.empty()) {
    std::printf("  warning: %zu structures have no voxel on the volume grid:", empty.size());
    for (const auto& s : empty) std::printf(" %s", s.c_str());
    std::printf("\n");
  }
  return 0;
}

}  // namespace at::app
