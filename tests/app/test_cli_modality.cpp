// --modality: the DICOM modality of a volume whose file records none (an MR as NIfTI or NRRD, the
// usual way MR is shared). It is kept with an imported dataset and read back on every open, so that
// density-weighted distances on MR, PT, NM or US come with the note that they assume CT-like values,
// as for a DICOM MR. A code DICOM's form does not allow, a file that records another modality, a
// built-in or an imported dataset given one: each refused in one line, the database byte-identical.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_checks.h"
#include "desktop_script.h"
#include "headless_desktop.h"
#include "intensity_notes.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/intensity.h"
#include "volume/nrrd_io.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

using test::quotedPath;
using test::runAppJson;

// VTK's headsq as a detached NRRD (header and data files) copied into `folder`: a volume file that
// records no modality.
fs::path copyHeadNrrd(const fs::path& folder) {
  fs::create_directories(folder);
  for (const auto& e : fs::directory_iterator(test::sharedData("headsq/nrrd")))
    if (e.is_regular_file()) fs::copy_file(e.path(), folder / e.path().filename());
  return folder / "quarter.nhdr";
}

// A label map on the head's grid (label 1 "ball": the voxels within 4 of the grid's centre) and its
// names, in `dir`: the structure the density-weighted distances start from. Returns the options
// that give them.
std::string writeBallLabels(const fs::path& dir, const fs::path& volume) {
  DatasetFiles files;
  files.volumePath = volume.string();
  auto read = openDatasetFiles(files);
  REQUIRE_MESSAGE(read, test::errorText(read));
  FloatVolume labels(read->volume.geometry, 0.0f);
  const Dims d = labels.dims();
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const int di = i - d.x / 2, dj = j - d.y / 2, dk = k - d.z / 2;
        if (di * di + dj * dj + dk * dk <= 16) labels.at(i, j, k) = 1.0f;
      }
  REQUIRE(writeNrrd((dir / "labels.nrrd").string(), labels, ScalarKind::UInt16));
  std::ofstream(dir / "names.json") << R"({"1": "ball"})";
  return " --labels " + quotedPath(dir / "labels.nrrd") + " --names " + quotedPath(dir / "names.json");
}

// The head NRRD copied into a fresh folder, with the ball's label map beside it.
struct HeadFiles {
  test::TempDir dir{"at-modality"};
  fs::path nrrd = copyHeadNrrd(dir / "head");
  fs::path db = dir / "t.db";
  std::string labels = writeBallLabels(dir.path(), nrrd);  // the options that give the labels
};

constexpr const char* kMrNote = "is MR: its intensities are not attenuation";

}  // namespace

TEST_CASE("Modality_Codes_XRayAndUnknownAreAttenuation_OthersGetTheNote") {
  for (const char* code : {"", "CT", "OT", "DX", "CR", "MG", "XA", "IO", "PX"}) {
    CAPTURE(code);
    CHECK(isAttenuationModality(code));
  }
  Dataset d;
  d.id = "scan";
  for (const char* code : {"MR", "PT", "NM", "US", "OPT", "SM"}) {
    CAPTURE(code);
    CHECK_FALSE(isAttenuationModality(code));
    d.intensity.modality = code;
    REQUIRE(app::densityWeightsNote(d));
    CHECK(app::densityWeightsNote(d)->rfind("'scan' is " + std::string(code) + ": its intensities are not attenuation", 0) ==
          0);
  }
  CHECK(parseModalityCode("mr").value_or("") == "MR");
  CHECK(parseModalityCode("PT").value_or("") == "PT");
  for (const char* bad : {"", " MR", "M-R", "MR\n", "\x1b[2J", "ABCDEFGHIJKLMNOPQ", "Mr\xc3\xa9"}) {
    CAPTURE(bad);
    const auto parsed = parseModalityCode(bad);
    REQUIRE_FALSE(parsed);
    CHECK(parsed.error().message.rfind("modality: '", 0) == 0);
    CHECK(parsed.error().message.find('\n') == std::string::npos);
  }
}

TEST_CASE("ImportCli_ModalityGiven_KeptWithTheDataset_NoteOnEveryOpen_AndInTheReimportHint") {
  if (!test::requireSharedData("headsq NRRD") || !test::requireAppBinary("import --modality")) return;
  const HeadFiles head;
  const fs::path &nrrd = head.nrrd, &db = head.db;
  const std::string& labels = head.labels;
  const auto imported =
      test::runApp("import --volume " + quotedPath(nrrd) + labels + " --name mrhead --modality mr --db " + quotedPath(db));
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  CHECK(imported.out.find("note: 'mrhead' " + std::string(kMrNote)) != std::string::npos);

  const nlohmann::json info = runAppJson("info mrhead --json --db " + quotedPath(db));
  CHECK(info["intensity"]["modality"] == "MR");
  CHECK(info["intensity"]["unit"] == "plain");
  CHECK(info["dataset"]["load_options"] == "--modality MR");
  // Every command that weighs distances by density says it, on the imported name and on the file.
  for (const std::string& dataset : {std::string("mrhead --db ") + quotedPath(db), quotedPath(nrrd) + labels + " --modality MR"}) {
    CAPTURE(dataset);
    const auto wdt = test::runApp("wdt " + dataset + " ball --backend cpu --json");
    REQUIRE_MESSAGE(wdt.exitCode == 0, wdt.err);
    CHECK(wdt.err.find(kMrNote) != std::string::npos);
  }
  const auto bare = test::runApp("wdt " + quotedPath(nrrd) + labels + " ball --backend cpu --json");
  REQUIRE_MESSAGE(bare.exitCode == 0, bare.err);
  CHECK(bare.err.find("not attenuation") == std::string::npos);
  // info on the file itself, told the modality.
  CHECK(runAppJson("info " + quotedPath(nrrd) + " --modality MR --json")["intensity"]["modality"] == "MR");
  CHECK(runAppJson("info " + quotedPath(nrrd) + " --json")["intensity"]["modality"] == "");

  // A file changed after the import: the refusal's re-import command keeps the modality.
  {
    std::ofstream header(nrrd, std::ios::app);
    header << "# changed\n";
  }
  const auto changed = test::runApp("info mrhead --db " + quotedPath(db));
  CHECK(changed.exitCode != 0);
  CHECK(changed.err.find("has changed since it was imported") != std::string::npos);
  CHECK(changed.err.find("--modality MR --name mrhead --replace") != std::string::npos);
}

TEST_CASE("ImportCli_ModalityRefused_InOneLine_DatabaseByteIdentical") {
  if (!test::requireSharedData("headsq") || !test::requireAppBinary("import --modality")) return;
  test::TempDir dir("at-modality");
  const fs::path nrrd = copyHeadNrrd(dir / "head");
  const std::string dicom = quotedPath(test::sharedData("headsq/dicom"));
  const fs::path db = dir / "t.db";
  REQUIRE(test::runApp("import --volume " + quotedPath(nrrd) + " --name head --db " + quotedPath(db)).exitCode == 0);
  // A DICOM series that records CT, given as CT: taken (the same code is no contradiction).
  REQUIRE(test::runApp("import --volume " + dicom + " --name headct --modality CT --db " + quotedPath(db)).exitCode == 0);
  const std::string before = test::readFile(db);
  for (const auto& [options, message] :
       {std::pair{"--volume " + quotedPath(nrrd) + " --name bad --modality 'M-R'", std::string("--modality: 'M-R' is not a DICOM modality code")},
        std::pair{"--volume " + quotedPath(nrrd) + " --name bad --modality ''", std::string("--modality: '' is not a DICOM modality code")},
        std::pair{"--volume " + quotedPath(nrrd) + " --name bad --modality ABCDEFGHIJKLMNOPQ", std::string("is not a DICOM modality code")},
        std::pair{"--volume " + quotedPath(nrrd) + " --name bad --modality \"$(printf 'MR\\n\\033[2J')\"",
                  std::string("is not a DICOM modality code")},
        std::pair{"--volume " + dicom + " --name bad --modality MR",
                  std::string("its DICOM Modality is CT, not the MR given")}}) {
    CAPTURE(options);
    test::checkOneLineError(test::runApp("import " + options + " --db " + quotedPath(db)), message);
    CHECK(test::readFile(db) == before);
  }
  // Commands on a file refuse the same; built-in and imported datasets take no modality.
  const std::string out = quotedPath(dir / "s.png");
  test::checkOneLineError(test::runApp("slice " + dicom + " --modality PT --axis z --index 40 --out " + out),
                          "its DICOM Modality is CT, not the PT given");
  test::checkOneLineError(test::runApp("info " + dicom + " --modality PT"), "its DICOM Modality is CT, not the PT given");
  test::checkOneLineError(test::runApp("slice phantom:32 --modality MR --axis z --index 3 --out " + out),
                          "apply to datasets from files");
  test::checkOneLineError(test::runApp("slice head --db " + quotedPath(db) + " --modality MR --axis z --index 40 --out " + out),
                          "apply to datasets from files");
  test::checkOneLineError(test::runApp("info head --db " + quotedPath(db) + " --modality MR"), "--modality applies to files");
  CHECK(test::readFile(db) == before);
  CHECK_FALSE(fs::exists(dir / "s.png"));
}

// The desktop's Import window takes the modality as the command line does, and the explore view of
// the imported dataset then carries the note.
TEST_CASE("DesktopImport_ModalityGiven_TheDatasetCarriesTheNote") {
  if (!test::requireSharedData("headsq NRRD") || !test::requireAppBinary("desktop import") || !test::requireXvfb()) return;
  test::TempDir dir("at-modality");
  const fs::path nrrd = copyHeadNrrd(dir / "head");
  test::DesktopOptions desktop;
  desktop.db = dir / "t.db";
  const test::DesktopRun shown = test::runDesktopScript(
      dir,
      {{"actions",
        {{{"do", "import"}, {"volume", nrrd.string()}, {"name", "pethead"}, {"modality", "pt"}},
         {{"do", "open_imported"}},
         {{"do", "wait_field"}}}}},
      desktop);
  REQUIRE_MESSAGE(shown.exitCode == 0, shown.err);
  CHECK(shown.err.find("'pethead' is PT: its intensities are not attenuation") != std::string::npos);
  CHECK(runAppJson("info pethead --json --db " + quotedPath(dir / "t.db"))["intensity"]["modality"] == "PT");
}

// The note stays with the dataset under its name as long as it is shown, whatever notes come after,
// and goes with it when another dataset is opened.
TEST_CASE("DesktopCaution_StaysWithTheDatasetItConcerns") {
  if (!test::requireSharedData("headsq NRRD") || !test::requireAppBinary("import --modality")) return;
  const HeadFiles head;
  const fs::path &nrrd = head.nrrd, &db = head.db;
  const std::string& labels = head.labels;
  REQUIRE(test::runApp("import --volume " + quotedPath(nrrd) + labels + " --name pthead --modality PT --db " + quotedPath(db))
              .exitCode == 0);
  test::HeadlessOptions options;
  options.dataset = "pthead";
  options.db = db;
  std::vector<std::pair<std::string, std::optional<std::string>>> seen;  // (dataset shown, caution) per frame
  options.drawPanels = [&](app::DesktopModel& model) { seen.emplace_back(model.dataset().id, model.datasetCaution()); };
  const auto run = test::runHeadless({{"actions",
                                       {{{"do", "select"}, {"structure", "ball"}},
                                        {{"do", "wait_field"}},
                                        {{"do", "open_dataset"}, {"name", "phantom"}},
                                        {{"do", "wait"}, {"ms", 30}}}}},
                                     options);
  INFO(run.messages);
  REQUIRE(run.exitCode == 0);
  std::size_t onPt = 0, onPhantom = 0;
  for (const auto& [dataset, caution] : seen) {
    CAPTURE(dataset);
    if (dataset == "pthead") {
      ++onPt;
      REQUIRE(caution);
      CHECK(caution->rfind("'pthead' is PT: its intensities are not attenuation", 0) == 0);
    } else {
      ++onPhantom;
      CHECK_FALSE(caution);
    }
  }
  CHECK(onPt > 0);
  CHECK(onPhantom > 0);
}
