#include "study_session.h"

#include <algorithm>
#include <fstream>
#include <optional>

#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/printable_text.h"
#include "core/regular_file.h"
#include "data_paths.h"
#include "db/study_withdrawal.h"
#include "quiz/study_report.h"
#include "quiz/redcap_export.h"
#include "quiz/responses_long_reader.h"
#include "svg_raster.h"
#include "volume/png_image.h"

namespace at::app {

namespace fs = std::filesystem;

namespace {

fs::path shippedStudiesDir() { return dataSubdirectory("studies"); }

std::vector<fs::path> shippedStudyFiles() {
  std::vector<fs::path> files;
  std::error_code ec;
  if (!fs::is_directory(shippedStudiesDir(), ec)) return files;
  for (const auto& entry : fs::directory_iterator(shippedStudiesDir(), ec))
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

Result<std::optional<quiz::StudyProtocol>> findStudyDefinition(const std::string& spec) {
  if (fs::is_regular_file(spec)) {
    auto p = quiz::loadStudyProtocol(spec);
    if (!p) return tl::unexpected(p.error());
    return std::optional<quiz::StudyProtocol>(std::move(*p));
  }
  for (const fs::path& f : shippedStudyFiles()) {
    auto p = quiz::loadStudyProtocol(f.string());
    if (p && p->id == spec) return std::optional<quiz::StudyProtocol>(std::move(*p));
  }
  return std::optional<quiz::StudyProtocol>();
}

Result<quiz::StudyProtocol> resolveStudy(db::Database& database, const std::string& spec) {
  auto stored = db::findStudy(database, spec);
  if (!stored) return tl::unexpected(stored.error());
  if (*stored) return **stored;
  auto loaded = findStudyDefinition(spec);
  if (!loaded) return tl::unexpected(loaded.error());
  if (!*loaded) return fail("no study '" + spec + "' (not stored in " + db::pathOf(database) + ", not a file, not shipped)");
  // A file naming a stored study id resolves to the stored one when unchanged; saveStudy refuses
  // design changes once participants exist.
  if (auto s = db::saveStudy(database, **loaded); !s) return tl::unexpected(s.error());
  return **loaded;
}

Result<std::vector<quiz::StudyResponseRow>> readStudyBundle(const fs::path& folder, const quiz::StudyProtocol& design) {
  const std::string where = printableText(folder.string(), 200);
  const fs::path sidecarPath = folder / "responses_long.json", tablePath = folder / "responses_long.csv";
  auto sidecarText = readRegularFile(sidecarPath.string(), where + "/responses_long.json", std::size_t(4) << 20);
  if (!sidecarText) return tl::unexpected(sidecarText.error());
  const auto sidecar = nlohmann::json::parse(*sidecarText, nullptr, false);
  const std::string sidecarName = where + "/responses_long.json";
  if (sidecar.is_discarded() || !sidecar.is_object()) return fail(sidecarName + ": not a JSON object");
  const auto field = [&](const char* key) {
    const auto it = sidecar.find(key);
    return it != sidecar.end() && it->is_string() ? it->get<std::string>() : std::string();
  };
  if (field("file") != "responses_long.csv")
    return fail(sidecarName + ": field 'file' is not \"responses_long.csv\" (not a study export's sidecar)");
  if (field("study") != design.id)
    return fail(ErrorKind::Conflict, sidecarName + ": the bundle is of study '" + printableText(field("study"), 80) +
                                         "', not '" + design.id + "'");
  // The levels the export listed must be the study's (an export of another version of the study).
  std::vector<std::string> structures, items, conditions;
  if (sidecar.contains("columns") && sidecar["columns"].is_array())
    for (const auto& column : sidecar["columns"]) {
      if (!column.is_object() || !column.contains("levels")) continue;
      const auto nameIt = column.find("name");
      const std::string name = nameIt != column.end() && nameIt->is_string() ? nameIt->get<std::string>() : "";
      const auto& levels = column["levels"];
      if (name == "structure" && levels.is_array())
        for (const auto& v : levels) structures.push_back(v.is_string() ? v.get<std::string>() : "");
      if ((name == "item" || name == "a_condition") && levels.is_object())
        for (auto it = levels.begin(); it != levels.end(); ++it) (name == "item" ? items : conditions).push_back(it.key());
    }
  std::vector<std::string> designItems, designConditions;
  for (const auto& item : design.items) designItems.push_back(item.id);
  for (const auto& condition : design.conditions) designConditions.push_back(condition.id);
  // nlohmann's objects are sorted by key: compare the item and condition ids as sets.
  std::sort(items.begin(), items.end());
  std::sort(designItems.begin(), designItems.end());
  std::sort(conditions.begin(), conditions.end());
  std::sort(designConditions.begin(), designConditions.end());
  if (structures != design.structures || items != designItems || conditions != designConditions)
    return fail(ErrorKind::Conflict, sidecarName + ": the bundle's structures, items or conditions are not those of "
                                                   "study '" + design.id + "' (exported from another version of it)");
  auto table = readRegularFile(tablePath.string(), where + "/responses_long.csv", std::size_t(1) << 30);
  if (!table) return tl::unexpected(table.error());
  return quiz::readResponsesLongCsv(*table, where + "/responses_long.csv", design);
}

std::vector<std::string> shippedStudyIds() {
  std::vector<std::string> ids;
  for (const fs::path& f : shippedStudyFiles())
    if (auto p = quiz::loadStudyProtocol(f.string())) ids.push_back(p->id);
  return ids;
}

namespace {

// The render mode a study condition shows: its id, else its preset suffix without the '_'.
Result<render::RenderMode> conditionMode(const quiz::StudyCondition& condition) {
  if (auto mode = render::parseRenderMode(condition.id)) return *mode;
  std::string suffix = condition.presetSuffix;
  if (!suffix.empty() && suffix.front() == '_') suffix.erase(0, 1);
  if (auto mode = render::parseRenderMode(suffix)) return *mode;
  return fail("condition '" + condition.id + "' names no render mode (neither its id nor its preset suffix '" +
              condition.presetSuffix + "' is wdt, bare, …), so its presets cannot be derived");
}

}  // namespace

Result<std::map<std::string, render::Preset>> loadStudyPresets(const render::PresetLibrary& library,
                                                               const quiz::StudyProtocol& protocol,
                                                               const StudyLevels& levels) {
  std::map<std::string, render::Preset> presets;
  std::optional<render::IntensityLevels> summary;  // computed at the first preset that is not written
  for (const std::string& structure : protocol.structures)
    for (int condition = 0; condition < 2; ++condition) {
      const std::string id = protocol.presetFor(structure, condition);
      std::error_code ec;
      if (fs::exists(library.dir() / (id + ".json"), ec) || !levels) {
        auto preset = library.load(id);
        if (!preset) return tl::unexpected(withContext("study " + protocol.id, preset.error()));
        presets[id] = *preset;
        continue;
      }
      auto mode = conditionMode(protocol.conditions.at(std::size_t(condition)));
      if (!mode) return tl::unexpected(withContext("study " + protocol.id, mode.error()));
      if (!summary) {
        auto computed = levels();
        if (!computed) return tl::unexpected(withContext("study " + protocol.id, computed.error()));
        summary = *computed;
      }
      presets[id] = render::derivedPreset(*summary, *mode, structure);
    }
  return presets;
}

db::RatingRecord makeRating(const quiz::StudyProtocol& protocol, const render::Preset& wdtPreset, int position,
                            const std::string& item, int ratingAsShown, double responseMs) {
  db::RatingRecord r;
  r.position = position;
  r.item = item;
  r.ratingAsShown = ratingAsShown;
  r.responseMs = responseMs;
  r.t = protocol.t;
  r.alpha = wdtPreset.alpha;
  r.beta = wdtPreset.lightingBeta;
  r.appVersion = AT_VERSION;
  return r;
}

Result<StudyExport> StudyExport::prepare(db::Database& database, const quiz::StudyProtocol& protocol,
                                         const fs::path& outDir) {
  std::error_code ec;
  fs::create_directories(outDir, ec);
  if (ec || !fs::is_directory(outDir)) return fail(outDir.string() + ": cannot create the output folder");
  auto rows = db::studyResponseRows(database, protocol);
  if (!rows) return tl::unexpected(rows.error());
  auto participants = db::studyParticipantRows(database, protocol.id);
  if (!participants) return tl::unexpected(participants.error());
  StudyExport e;
  e.protocol_ = protocol;
  e.rows_ = std::move(*rows);
  e.participantRows_ = std::move(*participants);
  e.participants_ = e.participantRows_.size();
  for (const auto& p : e.participantRows_) e.partial_ += p.complete ? 0 : 1;
  e.summary_ = quiz::summariseStudy(protocol, e.rows_);
  e.dir_ = outDir;
  e.names_ = {"responses_long.csv",    "responses_wide.csv", "responses_long.json",
              "redcap_dictionary.csv", "redcap_records.csv", "redcap_repeating_forms.csv",
              "summary.csv",           "summary.md",         "summary.svg",
              "summary.png"};
  auto withdrawn = db::studyWithdrawals(database, protocol.id);
  if (!withdrawn) return tl::unexpected(withdrawn.error());
  if (!withdrawn->empty()) {
    e.withdrawalsCsv_ = "participant_id,group,withdrawal,reason,withdrawn_at_utc\n";
    for (const db::StudyWithdrawal& w : *withdrawn)
      e.withdrawalsCsv_ += quiz::csvQuoted(w.participantId) + "," + quiz::csvQuoted(w.group) + "," + db::toString(w.kind) +
                           "," + quiz::csvQuoted(w.reason) + "," + w.at + "\n";
    e.names_.push_back("withdrawals.csv");
  }
  return e;
}

Status StudyExport::writeNext() {
  if (done()) return {};
  const std::string& name = names_[next_];
  const fs::path path = dir_ / name;
  Status st;
  switch (next_) {
    case 0: st = writeFileAtomically(path.string(), quiz::responsesLongCsv(rows_)); break;
    case 1: st = writeFileAtomically(path.string(), quiz::responsesWideCsv(protocol_, rows_)); break;
    case 2: st = writeFileAtomically(path.string(), quiz::responsesLongJsonSidecar(protocol_)); break;
    case 3: st = writeFileAtomically(path.string(), quiz::redcapDictionaryCsv(protocol_)); break;
    case 4: st = writeFileAtomically(path.string(), quiz::redcapRecordsCsv(protocol_, participantRows_, rows_)); break;
    case 5: st = writeFileAtomically(path.string(), quiz::redcapRepeatingFormsCsv()); break;
    case 6: st = writeFileAtomically(path.string(), quiz::summaryCsv(summary_)); break;
    case 7: st = writeFileAtomically(path.string(), quiz::summaryMarkdown(protocol_, summary_, participants_, partial_)); break;
    case 8: st = writeFileAtomically(path.string(), quiz::summarySvg(protocol_, summary_)); break;
    case 10: st = writeFileAtomically(path.string(), withdrawalsCsv_); break;
    default: {
      auto chart = summaryChart(protocol_, summary_);
      st = chart ? writePng(path.string(), *chart) : Status(tl::unexpected(chart.error()));
      break;
    }
  }
  if (!st) return st;
  ++next_;
  return {};
}

Result<RgbImage> summaryChart(const quiz::StudyProtocol& protocol, const quiz::StudySummary& summary) {
  return rasteriseSvg(quiz::summarySvg(protocol, summary));
}

Status StudyExport::discardWritten() {
  for (; next_ > 0; --next_) {
    std::error_code ec;
    const fs::path path = dir_ / names_[next_ - 1];
    if (!fs::remove(path, ec) && ec) return fail(path.string() + ": cannot remove (" + ec.message() + ")");
  }
  return {};
}

}  // namespace at::app
