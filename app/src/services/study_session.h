// What the terminal study runner (cmd_study.cpp) and the desktop study panel (study_panel.cpp)
// share: finding a study, its presets, one rating's record, and the coordinator's export written
// one file at a time (so a UI can show "[k/8] file" between steps).
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "db/connection.h"
#include "db/study_store.h"
#include "quiz/study_report.h"
#include "render/derived_preset.h"
#include "render/preset.h"
#include "core/error.h"
#include "volume/png_image.h"

namespace at::app {

// The study: a stored id, else a study JSON file, else a shipped study (data/studies) with that
// id. Files and shipped studies are stored (saveStudy) before they are returned.
Result<quiz::StudyProtocol> resolveStudy(db::Database& database, const std::string& spec);
// A study JSON file, else a shipped study with that id (nothing stored); nullopt when neither.
Result<std::optional<quiz::StudyProtocol>> findStudyDefinition(const std::string& spec);

// The long table of an export bundle (the folder `study export --out` wrote) of `design`'s study,
// read strictly (quiz/responses_long_reader.h). Its sidecar responses_long.json must name the
// study and list its structures, items and conditions (Conflict otherwise).
Result<std::vector<quiz::StudyResponseRow>> readStudyBundle(const std::filesystem::path& folder,
                                                            const quiz::StudyProtocol& design);

// Ids of the shipped studies (data/studies/*.json that parse), in file-name order.
std::vector<std::string> shippedStudyIds();

// The intensity levels of the dataset a study is shown on, asked for only when a preset has to be
// derived (render/derived_preset.h).
using StudyLevels = std::function<Result<render::IntensityLevels>()>;

// Both presets of every structure of the study, by preset id: the library's preset of that id
// where one is written, else — given `levels` — the preset derived from the dataset's intensities
// for the condition's mode (the condition id, or its preset suffix without the '_', names a
// render mode: "wdt", "bare", …), so that a study runs on any labelled dataset. Without `levels`
// a missing preset is an error naming it.
Result<std::map<std::string, render::Preset>> loadStudyPresets(const render::PresetLibrary& library,
                                                               const quiz::StudyProtocol& protocol,
                                                               const StudyLevels& levels = {});

// One rating as it is stored: the item's rating as shown with the WDT preset's render
// parameters (α, β) and the study's t.
db::RatingRecord makeRating(const quiz::StudyProtocol& protocol, const render::Preset& wdtPreset, int position,
                            const std::string& item, int ratingAsShown, double responseMs);

// The summary chart as pixels: the SVG of quiz::summarySvg rasterised (the export's summary.png and
// the coordinator panel show the same labelled chart).
Result<RgbImage> summaryChart(const quiz::StudyProtocol& protocol, const quiz::StudySummary& summary);

// The coordinator's export of one study: 10 files (long and wide CSV with the JSON sidecar of the
// long one; the REDCap dictionary, records and repeating-form setting; summary CSV/Markdown/SVG/PNG),
// none of them with a withdrawn or excluded participant's data, and then, when the study has such
// participants, withdrawals.csv: who, withdrawn or excluded, why and when (no data of theirs).
// `prepare` reads the database once; `writeNext` writes one file per call.
class StudyExport {
 public:
  static Result<StudyExport> prepare(db::Database& database, const quiz::StudyProtocol& protocol,
                                     const std::filesystem::path& outDir);
  std::size_t fileCount() const { return names_.size(); }
  std::size_t written() const { return next_; }
  bool done() const { return next_ >= names_.size(); }
  // Name of the file `writeNext` writes next ("responses_long.csv"), empty when done.
  std::string nextName() const { return done() ? std::string() : names_[next_]; }
  Status writeNext();
  // Removes the files this export has written so far, so that a cancelled export leaves no
  // partial set behind; an error names the file that could not be removed.
  Status discardWritten();
  const quiz::StudySummary& summary() const { return summary_; }
  std::size_t rowCount() const { return rows_.size(); }
  std::size_t participantCount() const { return participants_; }

 private:
  quiz::StudyProtocol protocol_;
  std::vector<quiz::StudyResponseRow> rows_;
  std::vector<quiz::StudyParticipantRow> participantRows_;
  quiz::StudySummary summary_;
  std::size_t participants_ = 0, partial_ = 0;
  std::filesystem::path dir_;
  std::vector<std::string> names_;
  std::string withdrawalsCsv_;
  std::size_t next_ = 0;
};

}  // namespace at::app
