// anatomy-tutor import: registers a dataset (volume + optional labels and names) in the database
// through importDataset (dataset_import.h), which the desktop app's import panel runs as well.
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "cli_args.h"
#include "commands.h"
#include "dataset_import.h"
#include "db/connection.h"
#include "intensity_notes.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kImportHelp =
    "usage: anatomy-tutor import --volume PATH --name NAME [--labels PATH] [--names NAMES.json]\n"
    "                            [--species SPECIES] [--replace] [--skip-unreadable] [--nrrd-data DIR]\n"
    "                            [--intensity auto|hu|plain] [--intercept B] [--slope A] [--modality CODE]\n"
    "                            [--db PATH]\n\n"
    "Registers a dataset in the database: the volume (a DICOM folder, .nii, .nii.gz, .nrrd, .nhdr, .inv3),\n"
    "an optional label map on the same anatomy (any of those formats or DICOM SEG) and an optional\n"
    "JSON of label names ({\"1\": \"spleen\", …}). Both are loaded first to check that they align.\n"
    "The database keeps absolute paths, SHA-256 checksums and the geometry, never pixels or patient\n"
    "identifiers. Afterwards the dataset's NAME works wherever a DATASET is asked for. Every command\n"
    "that opens it checks the files' checksums first: a file changed since the import is refused.\n\n"
    "  --replace  register NAME again, replacing the dataset of that name (after its files changed)\n"
    "  --skip-unreadable, --nrrd-data DIR: as for `structures`; kept with the dataset for later opens\n"
    "  --species  human (default), dog, cat, horse, … (lower-case letters, '-' and '_')\n"
    "  --intensity  auto (default): CT in HU or plain intensities as the file tells; hu or plain forces one\n"
    "  --intercept, --slope  for values the file does not calibrate (a raw volume, a CT stored without\n"
    "             its rescale, e.g. --intercept -1024): values become value x slope + intercept; reaching\n"
    "             air (<= -500) reads them as CT in HU. All three are kept with the dataset for later opens\n"
    "  --modality  the DICOM modality of a volume whose file records none (a NIfTI or NRRD MR: MR), kept\n"
    "             too: on MR, PT, NM, US, … density-weighted distances come with a note that they assume CT\n"
    "  --db       database file (default: $XDG_DATA_HOME/anatomy-tutor/anatomy-tutor.db)\n";

}  // namespace

int runImport(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"volume", "labels", "names", "name", "species", "nrrd-data", "intensity", "intercept", "slope",
                                       "modality"},
                               {"replace", "skip-unreadable"});
  if (!args) return reportError("import: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kImportHelp);
    return 0;
  }
  if (!args->positional().empty()) return reportError("import: unexpected argument '" + args->positional()[0] + "'");
  const auto volume = args->value("volume");
  const auto name = args->value("name");
  if (!volume) return reportError("import: --volume PATH is required (see --help)");
  if (!name || name->empty()) return reportError("import: --name NAME is required (see --help)");

  ImportRequest request;
  request.volumePath = *volume;
  request.labelsPath = args->valueOr("labels", "");
  request.namesPath = args->valueOr("names", "");
  request.name = *name;
  request.species = args->valueOr("species", "human");
  request.replace = args->has("replace");
  request.skipUnreadableFiles = args->has("skip-unreadable");
  request.dataFolder = args->valueOr("nrrd-data", "");
  if (auto text = args->value("intensity")) {
    auto choice = parseIntensityChoice(*text);
    if (!choice) return reportError("import: --" + choice.error().message);
    request.intensity = *choice;
  }
  if (auto text = args->value("modality")) {
    auto code = parseModalityCode(*text);  // (an empty one too: "as the file says" is leaving it out)
    if (!code) return reportError("import: --" + code.error().message);
    request.modality = *code;
  }
  for (const auto& [option, target] : {std::pair{"intercept", &request.intercept}, std::pair{"slope", &request.slope}}) {
    const auto text = args->value(option);
    if (!text) continue;
    char* end = nullptr;
    const double value = std::strtod(text->c_str(), &end);
    if (text->empty() || *end != '\0' || !std::isfinite(value))
      return reportError(std::string("import: --") + option + ": '" + *text + "' is not a number");
    *target = value;
  }
  auto database = db::openDatabase(args->db());
  if (!database) return reportError("import: " + database.error().message);
  auto imported = importDataset(*database, request);
  if (!imported) return reportError("import: " + imported.error().message);

  const db::DatasetRecord& record = imported->record;
  const Geometry& g = record.geometry;
  terminalPrintf("imported '%s' (%s): %s voxels, spacing %.3g x %.3g x %.3g mm, %s; %zu structures\n",
              record.name.c_str(), record.species.c_str(), g.dims.toString().c_str(), g.spacingMm[0], g.spacingMm[1],
              g.spacingMm[2], record.orientation.c_str(), imported->dataset.structures.size());
  terminalPrintf("  volume  %s  %s\n", record.volumePath.c_str(), record.volumeChecksum.c_str());
  if (!record.labelsPath.empty()) terminalPrintf("  labels  %s  %s\n", record.labelsPath.c_str(), record.labelsChecksum.c_str());
  for (const auto& note : imported->dataset.provenance.notes) terminalPrintf("  note: %s\n", note.c_str());
  if (const auto note = densityWeightsNote(imported->dataset)) terminalPrintf("  note: %s\n", note->c_str());
  for (const auto& warning : imported->dataset.provenance.warnings) terminalPrintf("  warning: %s\n", warning.c_str());
  if (!imported->emptyStructures.empty()) {
    terminalPrintf("  warning: %zu structures have no voxel on the volume grid:", imported->emptyStructures.size());
    for (const auto& s : imported->emptyStructures) terminalPrintf(" %s", s.c_str());
    terminalPrintf("\n");
  }
  return 0;
}

}  // namespace at::app
