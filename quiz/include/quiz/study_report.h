// Study exports for coordinators, as pure text (db/ gathers the rows; app/ writes the files and
// rasterises the SVG): the tidy long table, the wide table, a JSON sidecar describing every column,
// and the paper's Table-2 summary (rows = items, columns = groups and all) as CSV, Markdown and an
// SVG chart. The REDCap files are quiz/redcap_export.h. All output is deterministic: the same rows
// give the same bytes.
//
// Unit of analysis for the summary: the participant. For each participant and item the ratings
// over the structures they rated are averaged (on the paper's scale, 1 = prefer WDT … 5 = prefer
// bare); n, mean, SD, the 95 % t interval and the Wilcoxon signed-rank test against the midpoint
// are computed over those participant means, per group and for all participants together.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "quiz/likert_stats.h"
#include "quiz/study_protocol.h"

namespace at::quiz {

// One row per participant × structure × item.
struct StudyResponseRow {
  std::string participantId;
  std::string group;
  int session = 1;             // the participant's session in which this item was rated; 0 = not known
  std::string structure;
  std::string item;
  int ratingAb = 0;            // as shown: 1 = prefer A … 5 = prefer B
  int rating = 0;              // paper's scale: 1 = prefer WDT … 5 = prefer bare
  std::string aCondition;      // condition id shown as "A"
  int presentationOrder = 0;   // 1-based position of the structure for this participant
  std::string presetA, presetB;
  double t = 0, alpha = 0, beta = 0;
  double viewMsA = 0, viewMsB = 0;
  int toggles = 0;
  bool viewingMeasured = true; // false: the views were shown outside the program (files), times unknown
  double responseMs = 0;
  std::string timestampUtc;    // ISO 8601, e.g. 2026-11-22T05:01:02Z
  std::string appVersion;
  std::string comment;         // the participant's free-text comment on this structure (may be empty)
  bool participantComplete = true;  // false: the participant stopped before the end (partial data)
  // The render quality on screen at the rating (db::RatingRecord); unset: not known.
  std::optional<int> qualityLevel, qualityFullLevel;
  std::optional<double> qualityScale, settleMs;
};

// RFC 4180 cell: quoted when it holds a comma, quote, CR or LF (quotes doubled); a text cell that
// begins with '=', '+', '-', '@', TAB or CR is prefixed with an apostrophe so spreadsheets do not
// evaluate it as a formula.
std::string csvCell(const std::string& text);
// RFC 4180 cell without the formula guard, for files read by programs rather than spreadsheets
// (REDCap's import keeps text as given).
std::string csvQuoted(const std::string& text);
// A number with at most `decimals` decimals, trailing zeros trimmed ("0.5", "12"); empty when not finite.
std::string csvNumber(double value, int decimals = 3);
// Joins cells with commas and ends the record with CRLF (RFC 4180).
std::string csvRecord(const std::vector<std::string>& cells);
// Parses RFC 4180 text back into records (used by tests and by re-imports).
std::vector<std::vector<std::string>> parseCsv(const std::string& text);

std::string responsesLongCsv(const std::vector<StudyResponseRow>& rows);
// The long table's column names in order (its header); quiz/responses_long_reader.h reads it back.
const std::vector<std::string>& responsesLongColumnNames();
std::string responsesWideCsv(const StudyProtocol& protocol, const std::vector<StudyResponseRow>& rows);
std::string responsesLongJsonSidecar(const StudyProtocol& protocol);

struct SummaryCell {
  std::string item;
  std::string group;           // a group name or "all"
  LikertSummary stats;
  std::string preferred;       // "WDT", "bare" (p < 0.05 and mean below/above the midpoint) or "none"
};

struct StudySummary {
  std::vector<std::string> items;    // protocol order
  std::vector<std::string> columns;  // groups in protocol order, then "all"
  std::vector<SummaryCell> cells;    // items × columns, row-major
  const SummaryCell& at(std::size_t item, std::size_t column) const { return cells[item * columns.size() + column]; }
};

StudySummary summariseStudy(const StudyProtocol& protocol, const std::vector<StudyResponseRow>& rows);
std::string summaryCsv(const StudySummary& summary);
// The Table-2 summary as Markdown. Every text from the study definition (title, ids, groups, item
// wording) is written through markdownText, so a title such as "# <img src=x>" or "a | b" stays
// text and cannot add headings, HTML or table cells.
std::string summaryMarkdown(const StudyProtocol& protocol, const StudySummary& summary, std::size_t participants,
                            std::size_t partialParticipants);
// Text as literal Markdown inline content: one line (line breaks become spaces, other control
// characters are dropped), Markdown punctuation backslash-escaped, '&' and angle brackets written
// as HTML entities.
std::string markdownText(const std::string& text);

// The chart: one row per item, a 1–5 axis from "prefer WDT" (left) to "prefer bare" (right), a
// marker per column (group/all) at its mean with its 95 % interval as a bar.
std::string summarySvg(const StudyProtocol& protocol, const StudySummary& summary);

struct ChartLayout {
  int width = 900, rowHeight = 70, top = 40, bottom = 72, left = 220, right = 40;
  // x pixel of a scale value (1..5) and y pixel of the marker for (item, column).
  int xOf(double value, const StudyScale& scale) const;
  int yOf(std::size_t item, std::size_t column, std::size_t columns) const;
  int height(std::size_t items) const { return top + int(items) * rowHeight + bottom; }
};
// Colour of each column's markers.
std::array<std::uint8_t, 3> chartColumnColour(std::size_t column);

}  // namespace at::quiz
