#include "label_output.h"

#include <ctime>

#include "core/strings.h"
#include "db/checksum.h"
#include "db/dataset_store.h"
#include "volume/label_writers.h"
#include "volume/nifti_io.h"

namespace at::app {

namespace fs = std::filesystem;

Status checkLabelsPath(const fs::path& out) {
  const std::string name = out.filename().string();
  if (str::endsWith(name, ".seg.nrrd") || str::endsWith(name, ".nii") || str::endsWith(name, ".nii.gz")) return {};
  return fail("--out '" + out.string() + "': use a .nii, .nii.gz or .seg.nrrd file name");
}

Status writeLabelsFile(const fs::path& out, const LabelMap& labels, const std::vector<Structure>& structures) {
  if (auto ok = checkLabelsPath(out); !ok) return ok;
  if (str::endsWith(out.filename().string(), ".seg.nrrd")) return writeSegNrrd(out.string(), labels, structures);
  return writeNiftiLabels(out.string(), labels);
}

Result<std::string> storeDatasetLabels(db::Database& database, const std::string& datasetName, const LabelMap& labels,
                                       const std::vector<Structure>& structures, const db::ReviewStates* review) {
  auto record = db::findDataset(database, datasetName);
  if (!record) return tl::unexpected(record.error());
  if (!*record)
    return fail(ErrorKind::NotFound,
                "'" + datasetName + "' is not an imported dataset (anatomy-tutor import registers one)");
  if (db::backendOf(database) != db::Backend::Sqlite)
    return fail(ErrorKind::Unavailable, "labels are stored in a folder beside a SQLite database; on a class server, "
                                        "export them to a file (--out) and import that on each machine");
  const fs::path folder = fs::absolute(fs::path(db::pathOf(database)).parent_path() / "labels");
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) return fail(ErrorKind::Io, "cannot create " + folder.string() + " (" + ec.message() + ")");
  char stamp[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(stamp, sizeof stamp, "%Y%m%dT%H%M%SZ", std::gmtime(&now));
  const fs::path labelsPath = folder / (str::identifier(datasetName) + "-" + stamp + ".nii.gz");
  const fs::path namesPath = folder / (str::identifier(datasetName) + "-" + stamp + ".names.json");
  if (auto ok = writeNiftiLabels(labelsPath.string(), labels); !ok) return tl::unexpected(ok.error());
  if (auto ok = writeLabelNames(namesPath.string(), structures); !ok) return tl::unexpected(ok.error());
  auto checksum = db::checksumPath(labelsPath.string());
  if (!checksum) return tl::unexpected(checksum.error());
  if (auto ok = db::saveDatasetLabels(database, datasetName, labelsPath.string(), *checksum, namesPath.string(), structures,
                                      review);
      !ok)
    return tl::unexpected(ok.error());
  return labelsPath.string();
}

}  // namespace at::app
