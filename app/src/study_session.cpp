#include "study_session.h"

#include <algorithm>
#include <fstream>
#include <optional>

#include "commands.h"
#include "data_paths.h"
#include "quiz/redcap_export.h"
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

Result<quiz::StudyProtocol> resolveStudy(db::Database& database, const std::string& spec) {
  auto stored = db::findStudy(database, spec);
  if (!stored) return tl::unexpected(stored.error());
  if (*stored) return **stored;
  std::optional<quiz::StudyProtocol> loaded;
  if (fs::is_regular_file(spec)) {
    auto p = quiz::loadStudyProtocol(spec);
    if (!p) return tl::unexpected(p.error());
    loaded = *p;
  } else {
    for (const fs::path& f : shippedStudyFiles()) {
      auto p = quiz::loadStudyProtocol(f.string());
      if (p && p->id == spec) {
        loaded = *p;
        break;
      }
    }
  }
  if (!loaded) return fail("no study '" + spec + "' (not stored in " + db::pathOf(database) + ", not a file, not shipped)");
  // A file naming a stored study id resolves to the stored one when unchanged; saveStudy refuses
  // design changes once participants exist.
  if (auto s = db::saveStudy(database, *loaded); !s) return tl::unexpected(s.error());
  return *loaded;
}

std::vector<std::string> shippedStudyIds() {
  std::vector<std::string> ids;
  for (const fs::path& f : shippedStudyFiles())
    if (auto p = quiz::loadStudyProtocol(f.string())) ids.push_back(p->id);
  return ids;
}

Result<std::map<std::string, render::Preset>> loadStudyPresets(const render::PresetLibrary& library,
                                                               const quiz::StudyProtocol& protocol) {
  std::map<std::string, render::Preset> presets;
  for (const std::string& structure : protocol.structures)
    for (int condition = 0; condition < 2; ++condition) {
      const std::string id = protocol.presetFor(structure, condition);
      auto preset = library.load(id);
      if (!preset) return tl::unexpected(withContext("study " + protocol.id, preset.error()));
      presets[id] = *preset;
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

Status writeFileAtomically(const fs::path& path, const std::string& content) {
  const fs::path temp = path.string() + ".part";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) return fail(temp.string() + ": cannot write");
    out.write(content.data(), std::streamsize(content.size()));
    if (!out) return fail(temp.string() + ": write failed (disk full?)");
  }
  std::error_code ec;
  fs::rename(temp, path, ec);
  if (ec) return fail(path.string() + ": cannot replace (" + ec.message() + ")");
  return {};
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
  return e;
}

Status StudyExport::writeNext() {
  if (done()) return {};
  const std::string& name = names_[next_];
  const fs::path path = dir_ / name;
  Status st;
  switch (next_) {
    case 0: st = writeFileAtomically(path, quiz::responsesLongCsv(rows_)); break;
    case 1: st = writeFileAtomically(path, quiz::responsesWideCsv(protocol_, rows_)); break;
    case 2: st = writeFileAtomically(path, quiz::responsesLongJsonSidecar(protocol_)); break;
    case 3: st = writeFileAtomically(path, quiz::redcapDictionaryCsv(protocol_)); break;
    case 4: st = writeFileAtomically(path, quiz::redcapRecordsCsv(protocol_, participantRows_, rows_)); break;
    case 5: st = writeFileAtomically(path, quiz::redcapRepeatingFormsCsv()); break;
    case 6: st = writeFileAtomically(path, quiz::summaryCsv(summary_)); break;
    case 7: st = writeFileAtomically(path, quiz::summaryMarkdown(protocol_, summary_, participants_, partial_)); break;
    case 8: st = writeFileAtomically(path, quiz::summarySvg(protocol_, summary_)); break;
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
