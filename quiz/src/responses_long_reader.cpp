#include "quiz/responses_long_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include "core/printable_text.h"

namespace at::quiz {

namespace {

// Column positions of the long table (responsesLongColumnNames).
enum Col : std::size_t {
  kParticipant, kGroup, kSession, kStructure, kItem, kRatingAb, kRating, kACondition, kOrder, kPresetA, kPresetB,
  kT, kAlpha, kBeta, kViewA, kViewB, kToggles, kResponseMs, kTimestamp, kAppVersion, kComment, kComplete,
  kQualityLevel, kQualityFullLevel, kQualityScale, kSettleMs, kColumnCount
};
// Bounds of the numbers: times (a year in ms) and render parameters.
constexpr double kLongestMs = 365.0 * 24 * 3600 * 1000, kLargestParameter = 1e6;
// Exports written before the render quality was recorded end at participant_complete.
constexpr std::size_t kColumnsWithoutQuality = kQualityLevel;

// Strict RFC 4180: records of cells; a quoted cell may hold commas, quotes (doubled) and line
// breaks; records end with CRLF or LF. `firstRow` numbers the records for errors.
class CsvRecords {
 public:
  CsvRecords(const std::string& text, std::string source) : text_(text), source_(std::move(source)) {
    if (text_.compare(0, 3, "\xEF\xBB\xBF") == 0) at_ = 3;  // a byte order mark from a spreadsheet
  }
  bool done() const { return at_ >= text_.size(); }
  int row() const { return row_; }

  // The next record; `row()` is its number (1 = first).
  Result<std::vector<std::string>> next() {
    ++row_;
    std::vector<std::string> cells;
    std::string cell;
    while (true) {
      if (at_ < text_.size() && text_[at_] == '"') {
        ++at_;
        while (true) {
          if (at_ >= text_.size()) return failHere("a quoted cell is not closed before the end of the file");
          const char c = text_[at_++];
          if (c != '"') {
            cell += c;
          } else if (at_ < text_.size() && text_[at_] == '"') {
            cell += '"';
            ++at_;
          } else {
            break;
          }
        }
        if (at_ < text_.size() && text_[at_] != ',' && text_[at_] != '\r' && text_[at_] != '\n')
          return failHere("text after the closing quote of a cell");
      } else {
        while (at_ < text_.size() && text_[at_] != ',' && text_[at_] != '\r' && text_[at_] != '\n') {
          if (text_[at_] == '"') return failHere("a quote inside a cell that does not start with one");
          cell += text_[at_++];
        }
      }
      cells.push_back(std::move(cell));
      cell.clear();
      if (at_ >= text_.size()) break;
      const char c = text_[at_++];
      if (c == ',') continue;
      if (c == '\r') {
        if (at_ >= text_.size() || text_[at_] != '\n') return failHere("a carriage return outside quotes not followed by a line feed");
        ++at_;
      }
      break;
    }
    return cells;
  }

 private:
  tl::unexpected<Error> failHere(const std::string& problem) const {
    return fail(source_ + ": row " + std::to_string(row_) + ": " + problem);
  }
  const std::string& text_;
  std::string source_;
  std::size_t at_ = 0;
  int row_ = 0;
};

std::string unguarded(const std::string& cell) {
  if (cell.size() >= 2 && cell[0] == '\'' && std::string_view("=+-@\t\r").find(cell[1]) != std::string_view::npos)
    return cell.substr(1);
  return cell;
}

std::string quoted(const std::string& text) { return "'" + printableText(text, 60) + "'"; }

// One record's cells with errors that name the row and the column.
class RowReader {
 public:
  RowReader(const std::string& source, int row, const std::vector<std::string>& cells)
      : source_(source), row_(row), cells_(cells) {}

  tl::unexpected<Error> problem(std::size_t column, const std::string& what) const {
    return fail(source_ + ": row " + std::to_string(row_) + ", column '" + responsesLongColumnNames()[column] +
                "': " + what);
  }
  const std::string& raw(std::size_t column) const { return cells_[column]; }
  bool blank(std::size_t column) const { return column >= cells_.size() || cells_[column].empty(); }
  std::string text(std::size_t column) const { return unguarded(cells_[column]); }

  Result<std::string> required(std::size_t column) const {
    if (blank(column)) return problem(column, "is empty");
    return text(column);
  }
  Result<int> integer(std::size_t column, int least, int most) const {
    const std::string& cell = cells_[column];
    int value = 0;
    const auto [end, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
    if (cell.empty() || ec != std::errc() || end != cell.data() + cell.size())
      return problem(column, quoted(cell) + " is not a whole number");
    if (value < least || value > most)
      return problem(column, std::to_string(value) + " is outside " + std::to_string(least) + "–" + std::to_string(most));
    return value;
  }
  // A number of at most `largest` in magnitude (no stored value comes near: times in ms, render
  // parameters, shares).
  Result<double> real(std::size_t column, bool mayBeNegative, double largest) const {
    const std::string& cell = cells_[column];
    double value = 0;
    const auto [end, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), value);
    if (cell.empty() || ec != std::errc() || end != cell.data() + cell.size() || !std::isfinite(value))
      return problem(column, quoted(cell) + " is not a finite number");
    if (!mayBeNegative && value < 0) return problem(column, quoted(cell) + " is negative");
    if (std::fabs(value) > largest) return problem(column, quoted(cell) + " is beyond " + csvNumber(largest));
    return value;
  }

 private:
  const std::string& source_;
  int row_;
  const std::vector<std::string>& cells_;
};

// ISO 8601 UTC to the second, as the export writes it: 2026-11-22T05:01:02Z.
bool isUtcTimestamp(const std::string& s) {
  if (s.size() != 20 || s[4] != '-' || s[7] != '-' || s[10] != 'T' || s[13] != ':' || s[16] != ':' || s[19] != 'Z')
    return false;
  for (std::size_t i : {0, 1, 2, 3, 5, 6, 8, 9, 11, 12, 14, 15, 17, 18})
    if (s[i] < '0' || s[i] > '9') return false;
  const auto two = [&](std::size_t i) { return (s[i] - '0') * 10 + (s[i + 1] - '0'); };
  return two(5) >= 1 && two(5) <= 12 && two(8) >= 1 && two(8) <= 31 && two(11) < 24 && two(14) < 60 && two(17) <= 60;
}

template <class T>
bool contains(const std::vector<T>& list, const std::string& id) {
  return std::any_of(list.begin(), list.end(), [&](const T& x) {
    if constexpr (std::is_same_v<T, std::string>) return x == id;
    else return x.id == id;
  });
}

Result<StudyResponseRow> readRow(const RowReader& in, const StudyProtocol& protocol, std::size_t columns) {
  StudyResponseRow r;
  auto text = [&](std::size_t column, std::string& into) -> Status {
    auto value = in.required(column);
    if (!value) return tl::unexpected(value.error());
    into = *value;
    return {};
  };
  if (auto s = text(kParticipant, r.participantId); !s) return tl::unexpected(s.error());
  if (auto valid = validParticipantId(r.participantId); !valid) return in.problem(kParticipant, valid.error().message);
  if (auto s = text(kGroup, r.group); !s) return tl::unexpected(s.error());
  if (!contains(protocol.groups, r.group)) return in.problem(kGroup, quoted(r.group) + " is not a group of the study");
  r.session = 0;
  if (!in.blank(kSession)) {
    auto session = in.integer(kSession, 1, 1 << 20);
    if (!session) return tl::unexpected(session.error());
    r.session = *session;
  }
  if (auto s = text(kStructure, r.structure); !s) return tl::unexpected(s.error());
  if (!contains(protocol.structures, r.structure))
    return in.problem(kStructure, quoted(r.structure) + " is not a structure of the study");
  if (auto s = text(kItem, r.item); !s) return tl::unexpected(s.error());
  if (!contains(protocol.items, r.item)) return in.problem(kItem, quoted(r.item) + " is not an item of the study");
  auto ratingAb = in.integer(kRatingAb, protocol.scale.min, protocol.scale.max);
  if (!ratingAb) return tl::unexpected(ratingAb.error());
  r.ratingAb = *ratingAb;
  if (auto s = text(kACondition, r.aCondition); !s) return tl::unexpected(s.error());
  if (!contains(protocol.conditions, r.aCondition))
    return in.problem(kACondition, quoted(r.aCondition) + " is not a condition of the study");
  auto rating = in.integer(kRating, protocol.scale.min, protocol.scale.max);
  if (!rating) return tl::unexpected(rating.error());
  r.rating = unblindRating(r.ratingAb, r.aCondition == protocol.conditions[0].id, protocol.scale);
  if (*rating != r.rating)
    return in.problem(kRating, std::to_string(*rating) + " does not unblind rating_ab " + std::to_string(r.ratingAb) +
                                   " with " + quoted(r.aCondition) + " shown as A (expected " +
                                   std::to_string(r.rating) + ")");
  auto order = in.integer(kOrder, 1, int(protocol.structures.size()));
  if (!order) return tl::unexpected(order.error());
  r.presentationOrder = *order;
  if (auto s = text(kPresetA, r.presetA); !s) return tl::unexpected(s.error());
  if (auto s = text(kPresetB, r.presetB); !s) return tl::unexpected(s.error());
  for (auto [column, into] : {std::pair{kT, &r.t}, std::pair{kAlpha, &r.alpha}, std::pair{kBeta, &r.beta}}) {
    auto value = in.real(column, true, kLargestParameter);
    if (!value) return tl::unexpected(value.error());
    *into = *value;
  }
  const int blanks = int(in.blank(kViewA)) + int(in.blank(kViewB)) + int(in.blank(kToggles));
  if (blanks != 0 && blanks != 3)
    return in.problem(in.blank(kViewA) ? kViewA : in.blank(kViewB) ? kViewB : kToggles,
                      "is blank while the other viewing columns are not (view_ms_a, view_ms_b and toggles are "
                      "all blank when the views were not measured)");
  r.viewingMeasured = blanks == 0;
  r.viewMsA = r.viewMsB = 0;
  r.toggles = 0;
  if (r.viewingMeasured) {
    auto a = in.real(kViewA, false, kLongestMs), b = in.real(kViewB, false, kLongestMs);
    if (!a) return tl::unexpected(a.error());
    if (!b) return tl::unexpected(b.error());
    auto toggles = in.integer(kToggles, 0, 1 << 30);
    if (!toggles) return tl::unexpected(toggles.error());
    r.viewMsA = *a;
    r.viewMsB = *b;
    r.toggles = *toggles;
  }
  auto response = in.real(kResponseMs, false, kLongestMs);
  if (!response) return tl::unexpected(response.error());
  r.responseMs = *response;
  if (auto s = text(kTimestamp, r.timestampUtc); !s) return tl::unexpected(s.error());
  if (!isUtcTimestamp(r.timestampUtc))
    return in.problem(kTimestamp, quoted(r.timestampUtc) + " is not an ISO 8601 UTC time such as 2026-11-22T05:01:02Z");
  r.appVersion = in.text(kAppVersion);
  r.comment = in.text(kComment);
  auto complete = in.integer(kComplete, 0, 1);
  if (!complete) return tl::unexpected(complete.error());
  r.participantComplete = *complete == 1;
  if (columns > kQualityLevel) {
    for (auto column : {kQualityLevel, kQualityFullLevel}) {
      if (in.blank(column)) continue;
      auto level = in.integer(column, 0, 64);
      if (!level) return tl::unexpected(level.error());
      (column == kQualityLevel ? r.qualityLevel : r.qualityFullLevel) = *level;
    }
    if (!in.blank(kQualityScale)) {
      auto scaleShare = in.real(kQualityScale, false, kLargestParameter);
      if (!scaleShare) return tl::unexpected(scaleShare.error());
      r.qualityScale = *scaleShare;
    }
    if (!in.blank(kSettleMs)) {
      auto settle = in.real(kSettleMs, false, kLongestMs);
      if (!settle) return tl::unexpected(settle.error());
      r.settleMs = *settle;
    }
  }
  return r;
}

// What every row of one participant × structure repeats.
struct TrialFacts {
  int row = 0;
  std::string structure, aCondition, presetA, presetB, comment;
  double viewMsA = 0, viewMsB = 0;
  int toggles = 0;
  bool viewingMeasured = true;
};

}  // namespace

Result<std::vector<StudyResponseRow>> readResponsesLongCsv(const std::string& text, const std::string& source,
                                                           const StudyProtocol& protocol) {
  const std::string name = printableText(source, 200);
  if (protocol.conditions.size() != 2) return fail(name + ": the study does not have two conditions");
  CsvRecords records(text, name);
  if (records.done()) return fail(name + ": empty file (expected the header of responses_long.csv)");
  auto header = records.next();
  if (!header) return tl::unexpected(header.error());
  const auto& names = responsesLongColumnNames();
  const std::size_t columns = header->size();
  const bool current = columns == kColumnCount, older = columns == kColumnsWithoutQuality;
  if (!current && !older)
    return fail(name + ": row 1 has " + std::to_string(columns) + " columns; the long table has " +
                std::to_string(kColumnCount) + " (or " + std::to_string(kColumnsWithoutQuality) +
                " in exports written before the quality columns)");
  for (std::size_t c = 0; c < columns; ++c)
    if ((*header)[c] != names[c])
      return fail(name + ": row 1, column " + std::to_string(c + 1) + " is " + quoted((*header)[c]) + ", expected '" +
                  names[c] + "'");

  std::vector<StudyResponseRow> rows;
  std::map<std::string, std::pair<int, StudyResponseRow>> participants;  // first row of each participant
  std::map<std::pair<std::string, int>, TrialFacts> trials;              // participant × position
  std::map<std::pair<std::string, std::string>, int> positionOf;         // participant × structure
  std::map<std::tuple<std::string, int, std::string>, int> rated;       // participant × position × item
  while (!records.done()) {
    auto cells = records.next();
    if (!cells) return tl::unexpected(cells.error());
    const int row = records.row();
    if (cells->size() != columns)
      return fail(name + ": row " + std::to_string(row) + " has " + std::to_string(cells->size()) +
                  " cells, the header " + std::to_string(columns));
    const RowReader in(name, row, *cells);
    auto r = readRow(in, protocol, columns);
    if (!r) return tl::unexpected(r.error());

    auto [first, isNew] = participants.try_emplace(r->participantId, row, *r);
    if (!isNew) {
      const StudyResponseRow& f = first->second.second;
      const std::string there = " on row " + std::to_string(first->second.first);
      if (f.group != r->group)
        return in.problem(kGroup, "participant " + quoted(r->participantId) + " is in group " + quoted(f.group) + there);
      if (f.participantComplete != r->participantComplete)
        return in.problem(kComplete, "differs from participant " + quoted(r->participantId) + "'s" + there);
    }
    const int position = r->presentationOrder - 1;
    const auto samePosition = positionOf.try_emplace({r->participantId, r->structure}, position).first;
    if (samePosition->second != position)
      return in.problem(kOrder, quoted(r->structure) + " was at presentation_order " +
                                    std::to_string(samePosition->second + 1) + " for participant " +
                                    quoted(r->participantId) + " on an earlier row");
    TrialFacts facts{row,      r->structure, r->aCondition, r->presetA,         r->presetB,
                     r->comment, r->viewMsA, r->viewMsB,    r->toggles, r->viewingMeasured};
    auto [trial, trialIsNew] = trials.try_emplace({r->participantId, position}, facts);
    if (!trialIsNew) {
      const TrialFacts& t = trial->second;
      const std::string there = " on row " + std::to_string(t.row) + " (the same participant and presentation_order)";
      if (t.structure != facts.structure) return in.problem(kStructure, "differs from " + quoted(t.structure) + there);
      if (t.aCondition != facts.aCondition) return in.problem(kACondition, "differs from " + quoted(t.aCondition) + there);
      if (t.presetA != facts.presetA) return in.problem(kPresetA, "differs from " + quoted(t.presetA) + there);
      if (t.presetB != facts.presetB) return in.problem(kPresetB, "differs from " + quoted(t.presetB) + there);
      if (t.viewingMeasured != facts.viewingMeasured || t.viewMsA != facts.viewMsA)
        return in.problem(kViewA, "differs from the value" + there);
      if (t.viewMsB != facts.viewMsB) return in.problem(kViewB, "differs from the value" + there);
      if (t.toggles != facts.toggles) return in.problem(kToggles, "differs from the value" + there);
      if (t.comment != facts.comment) return in.problem(kComment, "differs from the comment" + there);
    }
    if (auto [it, fresh] = rated.try_emplace({r->participantId, position, r->item}, row); !fresh)
      return in.problem(kItem, quoted(r->item) + " of " + quoted(r->structure) + " for participant " +
                                   quoted(r->participantId) + " is rated twice (also on row " +
                                   std::to_string(it->second) + ")");
    rows.push_back(std::move(*r));
  }
  return rows;
}

}  // namespace at::quiz
