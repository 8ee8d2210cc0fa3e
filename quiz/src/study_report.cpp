#include "quiz/study_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

namespace at::quiz {

// ---------------------------------------------------------------------------------------------
// CSV (RFC 4180)
// ---------------------------------------------------------------------------------------------

std::string csvCell(const std::string& text) {
  std::string cell = text;
  if (!cell.empty() && (cell[0] == '=' || cell[0] == '+' || cell[0] == '-' || cell[0] == '@' || cell[0] == '\t' ||
                        cell[0] == '\r'))
    cell.insert(cell.begin(), '\'');
  return csvQuoted(cell);
}

std::string csvQuoted(const std::string& cell) {
  const bool quote = cell.find_first_of(",\"\r\n") != std::string::npos;
  if (!quote) return cell;
  std::string out = "\"";
  for (char c : cell) {
    if (c == '"') out += '"';
    out += c;
  }
  out += '"';
  return out;
}

std::string csvRecord(const std::vector<std::string>& cells) {
  std::string line;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i) line += ',';
    line += cells[i];
  }
  return line + "\r\n";
}

std::vector<std::vector<std::string>> parseCsv(const std::string& text) {
  std::vector<std::vector<std::string>> records;
  std::vector<std::string> record;
  std::string cell;
  bool quoted = false, any = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    any = true;
    if (quoted) {
      if (c == '"') {
        if (i + 1 < text.size() && text[i + 1] == '"') {
          cell += '"';
          ++i;
        } else {
          quoted = false;
        }
      } else {
        cell += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      record.push_back(cell);
      cell.clear();
    } else if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') {
      record.push_back(cell);
      records.push_back(record);
      record.clear();
      cell.clear();
      any = false;
      ++i;
    } else {
      cell += c;
    }
  }
  if (any) {
    record.push_back(cell);
    records.push_back(record);
  }
  return records;
}

std::string csvNumber(double v, int decimals) {
  if (!std::isfinite(v)) return "";
  char buf[400];  // the largest double has 309 digits before the point
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  std::string s = buf;
  // Trim trailing zeros for stable, compact numbers ("0.500" → "0.5", "12.000" → "12").
  if (s.find('.') != std::string::npos) {
    while (!s.empty() && s.back() == '0') s.pop_back();
    if (!s.empty() && s.back() == '.') s.pop_back();
  }
  if (s == "-0") s = "0";
  return s;
}

namespace {

std::string number(double v, int decimals = 3) { return csvNumber(v, decimals); }

std::string pValueText(double p) {
  char buf[32];
  if (p < 0.001) return "<0.001";
  std::snprintf(buf, sizeof buf, "%.3f", p);
  return buf;
}

struct Column {
  const char* name;
  const char* type;
  const char* description;
  const char* units;
};

// The long table's columns, in order; the JSON sidecar and the data dictionary describe them.
const std::vector<Column>& longColumns() {
  static const std::vector<Column> columns = {
      {"participant_id", "string", "Pseudonymous participant id", ""},
      {"group", "categorical", "Participant group", ""},
      {"session", "integer", "The participant's session in which the item was rated (1 = first; blank = not known)", ""},
      {"structure", "categorical", "Structure id rated", ""},
      {"item", "categorical", "Questionnaire item id", ""},
      {"rating_ab", "integer", "Rating as shown to the participant: 1 = prefer A ... 5 = prefer B", "scale points"},
      {"rating", "integer", "Rating on the paper's scale: 1 = prefer WDT ... 5 = prefer bare structure", "scale points"},
      {"a_condition", "categorical", "Condition shown as A (the other was B)", ""},
      {"presentation_order", "integer", "Position of the structure in this participant's sequence (1-based)", ""},
      {"preset_a", "string", "Preset id shown as A", ""},
      {"preset_b", "string", "Preset id shown as B", ""},
      {"t", "number", "Blend t between data and distance transfer functions on screen", ""},
      {"alpha", "number", "Distance normalisation alpha on screen", ""},
      {"beta", "number", "Distance lighting beta on screen", ""},
      {"view_ms_a", "number", "Time condition A was on screen for this structure (blank: shown as files, not measured)", "ms"},
      {"view_ms_b", "number", "Time condition B was on screen for this structure (blank: shown as files, not measured)", "ms"},
      {"toggles", "integer", "Number of A/B toggles for this structure (blank: not measured)", ""},
      {"response_ms", "number", "Time from showing the item to the rating", "ms"},
      {"timestamp", "datetime", "When the rating was recorded (ISO 8601, UTC)", ""},
      {"app_version", "string", "Anatomy Tutor version that recorded the rating", ""},
      {"comment", "string", "Participant's optional free-text comment on the structure", ""},
      {"participant_complete", "integer", "1 if the participant finished the study, 0 if partial data", ""},
      {"quality_level", "integer", "Render quality level on screen when the item was rated (blank: not known)", ""},
      {"quality_full_level", "integer", "The full quality level (quality_level equal to it: rated at full quality)", ""},
      {"quality_scale", "number", "Resolution of the full level as a share of the view (1 = every pixel cast)", ""},
      {"settle_ms", "number", "Time from the rated side being shown to the full level on screen", "ms"},
  };
  return columns;
}

}  // namespace

const std::vector<std::string>& responsesLongColumnNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const Column& c : longColumns()) out.push_back(c.name);
    return out;
  }();
  return names;
}

std::string responsesLongCsv(const std::vector<StudyResponseRow>& rows) {
  std::vector<std::string> header;
  for (const Column& c : longColumns()) header.push_back(c.name);
  std::string out = csvRecord(header);
  for (const StudyResponseRow& r : rows) {
    const bool seen = r.viewingMeasured;
    out += csvRecord({csvCell(r.participantId), csvCell(r.group), r.session > 0 ? std::to_string(r.session) : "",
                      csvCell(r.structure), csvCell(r.item), std::to_string(r.ratingAb), std::to_string(r.rating),
                      csvCell(r.aCondition), std::to_string(r.presentationOrder), csvCell(r.presetA),
                      csvCell(r.presetB), number(r.t), number(r.alpha), number(r.beta),
                      seen ? number(r.viewMsA, 0) : "", seen ? number(r.viewMsB, 0) : "",
                      seen ? std::to_string(r.toggles) : "", number(r.responseMs, 0), csvCell(r.timestampUtc),
                      csvCell(r.appVersion), csvCell(r.comment), r.participantComplete ? "1" : "0",
                      r.qualityLevel ? std::to_string(*r.qualityLevel) : "",
                      r.qualityFullLevel ? std::to_string(*r.qualityFullLevel) : "",
                      r.qualityScale ? number(*r.qualityScale) : "", r.settleMs ? number(*r.settleMs, 0) : ""});
  }
  return out;
}

std::string responsesWideCsv(const StudyProtocol& protocol, const std::vector<StudyResponseRow>& rows) {
  // One row per participant: id, group, complete, then rating (paper scale) per structure × item,
  // and the comment per structure.
  std::vector<std::string> header = {"participant_id", "group", "participant_complete"};
  for (const std::string& s : protocol.structures) {
    for (const StudyItem& it : protocol.items) header.push_back(s + "__" + it.id);
    header.push_back(s + "__comment");
  }
  std::string out = csvRecord(header);
  std::vector<std::string> order;  // participants in first-appearance order (rows come sorted)
  std::map<std::string, std::map<std::string, std::string>> cells;
  std::map<std::string, std::pair<std::string, bool>> meta;
  for (const StudyResponseRow& r : rows) {
    if (!meta.count(r.participantId)) order.push_back(r.participantId);
    meta[r.participantId] = {r.group, r.participantComplete};
    cells[r.participantId][r.structure + "__" + r.item] = std::to_string(r.rating);
    if (!r.comment.empty()) cells[r.participantId][r.structure + "__comment"] = r.comment;
  }
  for (const std::string& p : order) {
    std::vector<std::string> record = {csvCell(p), csvCell(meta[p].first), meta[p].second ? "1" : "0"};
    for (std::size_t i = 3; i < header.size(); ++i) {
      auto it = cells[p].find(header[i]);
      record.push_back(it == cells[p].end() ? "" : csvCell(it->second));
    }
    out += csvRecord(record);
  }
  return out;
}

std::string responsesLongJsonSidecar(const StudyProtocol& protocol) {
  nlohmann::ordered_json j;
  j["file"] = "responses_long.csv";
  j["study"] = protocol.id;
  j["title"] = protocol.title;
  j["rows"] = "one per participant x structure x item";
  j["columns"] = nlohmann::ordered_json::array();
  for (const Column& c : longColumns()) {
    nlohmann::ordered_json col;
    col["name"] = c.name;
    col["type"] = c.type;
    col["description"] = c.description;
    if (c.units[0]) col["units"] = c.units;
    const std::string name = c.name;
    if (name == "group") col["levels"] = protocol.groups;
    if (name == "structure") col["levels"] = protocol.structures;
    if (name == "item") {
      nlohmann::ordered_json levels = nlohmann::ordered_json::object();
      for (const auto& it : protocol.items) levels[it.id] = it.wording;
      col["levels"] = levels;
    }
    if (name == "a_condition") {
      nlohmann::ordered_json levels = nlohmann::ordered_json::object();
      for (const auto& cond : protocol.conditions) levels[cond.id] = cond.label;
      col["levels"] = levels;
    }
    if (name == "rating_ab" || name == "rating") {
      col["minimum"] = protocol.scale.min;
      col["maximum"] = protocol.scale.max;
    }
    if (name == "rating_ab") {
      nlohmann::ordered_json anchors = nlohmann::ordered_json::object();
      for (const auto& [v, text] : protocol.scale.anchors) anchors[std::to_string(v)] = text;
      col["anchors"] = anchors;
    }
    if (name == "rating") {
      col["anchors"] = {{std::to_string(protocol.scale.min), "prefer " + protocol.conditions[0].id},
                        {std::to_string(protocol.scale.midpoint()), "no preference"},
                        {std::to_string(protocol.scale.max), "prefer " + protocol.conditions[1].id}};
    }
    j["columns"].push_back(col);
  }
  return j.dump(2) + "\n";
}

// ---------------------------------------------------------------------------------------------
// Summary (the paper's Table 2)
// ---------------------------------------------------------------------------------------------

StudySummary summariseStudy(const StudyProtocol& protocol, const std::vector<StudyResponseRow>& rows) {
  StudySummary summary;
  for (const auto& it : protocol.items) summary.items.push_back(it.id);
  summary.columns = protocol.groups;
  summary.columns.push_back("all");
  // participant → item → (sum, count); participant → group
  std::map<std::string, std::map<std::string, std::pair<double, int>>> perParticipant;
  std::map<std::string, std::string> groupOf;
  std::vector<std::string> participants;
  for (const StudyResponseRow& r : rows) {
    if (!groupOf.count(r.participantId)) participants.push_back(r.participantId);
    groupOf[r.participantId] = r.group;
    auto& acc = perParticipant[r.participantId][r.item];
    acc.first += r.rating;
    acc.second += 1;
  }
  const double midpoint = protocol.scale.midpoint();
  for (const std::string& item : summary.items) {
    for (const std::string& column : summary.columns) {
      std::vector<double> means;
      for (const std::string& p : participants) {
        if (column != "all" && groupOf[p] != column) continue;
        auto it = perParticipant[p].find(item);
        if (it == perParticipant[p].end() || it->second.second == 0) continue;
        means.push_back(it->second.first / it->second.second);
      }
      SummaryCell cell;
      cell.item = item;
      cell.group = column;
      cell.stats = summariseLikert(means, midpoint);
      cell.preferred = "none";
      if (cell.stats.n > 0 && cell.stats.pValue < 0.05) {
        if (cell.stats.mean < midpoint) cell.preferred = protocol.conditions[0].id;
        if (cell.stats.mean > midpoint) cell.preferred = protocol.conditions[1].id;
      }
      summary.cells.push_back(cell);
    }
  }
  return summary;
}

std::string summaryCsv(const StudySummary& summary) {
  std::string out = csvRecord({"item", "group", "n", "mean", "sd", "ci95_low", "ci95_high", "wilcoxon_w_plus",
                               "wilcoxon_n_nonzero", "wilcoxon_p", "wilcoxon_method", "preferred"});
  for (const SummaryCell& c : summary.cells) {
    const bool any = c.stats.n > 0;
    out += csvRecord({csvCell(c.item), csvCell(c.group), std::to_string(c.stats.n), any ? number(c.stats.mean, 4) : "",
                      c.stats.n > 1 ? number(c.stats.sd, 4) : "", c.stats.n > 1 ? number(c.stats.ciLow, 4) : "",
                      c.stats.n > 1 ? number(c.stats.ciHigh, 4) : "", any ? number(c.stats.wPlus, 1) : "",
                      std::to_string(c.stats.nonZero), any ? number(c.stats.pValue, 6) : "",
                      any ? (c.stats.exact ? "exact" : "normal") : "", csvCell(c.preferred)});
  }
  return out;
}

std::string markdownText(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (c == '\n' || c == '\r' || c == '\t') {
      out += ' ';
    } else if (u < 0x20 || u == 0x7f) {
      continue;
    } else if (c == '&') {
      out += "&amp;";
    } else if (c == '<') {
      out += "&lt;";
    } else if (c == '>') {
      out += "&gt;";
    } else if (std::strchr("\\`*_{}[]()#+-.!|~", c)) {
      out += '\\';
      out += c;
    } else {
      out += c;
    }
  }
  return out;
}

std::string summaryMarkdown(const StudyProtocol& protocol, const StudySummary& summary, std::size_t participants,
                            std::size_t partialParticipants) {
  const auto text = [](const std::string& s) { return markdownText(s); };
  std::string md = "# " + text(protocol.title.empty() ? protocol.id : protocol.title) + "\n\n";
  md += "Study " + text(protocol.id) + " on dataset " + text(protocol.dataset) + ": " + std::to_string(participants) +
        " participant(s)";
  if (partialParticipants) md += ", of whom " + std::to_string(partialParticipants) + " stopped before the end (partial data included)";
  md += ".\n\n";
  md += "Scale: " + std::to_string(protocol.scale.min) + " = prefer " + text(protocol.conditions[0].id) + " … " +
        std::to_string(protocol.scale.midpoint()) + " = no preference … " + std::to_string(protocol.scale.max) +
        " = prefer " + text(protocol.conditions[1].id) + ". Each cell: mean (SD) [95 % CI], n participants, Wilcoxon " +
        "signed-rank p against " + std::to_string(protocol.scale.midpoint()) +
        " (each participant's mean over the structures they rated).\n\n";
  md += "| item |";
  for (const auto& c : summary.columns) md += " " + text(c) + " |";
  md += "\n|---|";
  for (std::size_t i = 0; i < summary.columns.size(); ++i) md += "---|";
  md += "\n";
  for (std::size_t i = 0; i < summary.items.size(); ++i) {
    md += "| " + text(summary.items[i]) + " |";
    for (std::size_t c = 0; c < summary.columns.size(); ++c) {
      const SummaryCell& cell = summary.at(i, c);
      if (cell.stats.n == 0) {
        md += " — |";
        continue;
      }
      md += " " + number(cell.stats.mean, 2);
      if (cell.stats.n > 1)
        md += " (" + number(cell.stats.sd, 2) + ") [" + number(cell.stats.ciLow, 2) + ", " + number(cell.stats.ciHigh, 2) + "]";
      md += ", n=" + std::to_string(cell.stats.n) + ", p=" + pValueText(cell.stats.pValue);
      if (cell.preferred != "none") md += ", **prefers " + text(cell.preferred) + "**";
      md += " |";
    }
    md += "\n";
  }
  md += "\nItems:\n\n";
  for (const auto& it : protocol.items) md += "- " + text(it.id) + ": " + text(it.wording) + "\n";
  return md;
}

// ---------------------------------------------------------------------------------------------
// Chart
// ---------------------------------------------------------------------------------------------

int ChartLayout::xOf(double value, const StudyScale& scale) const {
  const double f = (value - scale.min) / double(scale.max - scale.min);
  return left + int(std::lround(f * double(width - left - right)));
}

int ChartLayout::yOf(std::size_t item, std::size_t column, std::size_t columns) const {
  const double slot = double(rowHeight) / double(columns + 1);
  return top + int(item) * rowHeight + int(std::lround(slot * double(column + 1)));
}

std::array<std::uint8_t, 3> chartColumnColour(std::size_t column) {
  static const std::array<std::uint8_t, 3> palette[] = {
      {0x1f, 0x77, 0xb4}, {0xd6, 0x27, 0x28}, {0x2c, 0xa0, 0x2c}, {0x94, 0x67, 0xbd}, {0x8c, 0x56, 0x4b}};
  return palette[column % 5];
}

namespace {
std::string hex(const std::array<std::uint8_t, 3>& c) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}
std::string xmlEscape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}
}  // namespace

std::string summarySvg(const StudyProtocol& protocol, const StudySummary& summary) {
  const ChartLayout L;
  const int H = L.height(summary.items.size());
  std::string svg = "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + std::to_string(L.width) + "\" height=\"" +
                    std::to_string(H) + "\" font-family=\"sans-serif\" font-size=\"13\">\n";
  svg += "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  svg += "<text x=\"" + std::to_string(L.left) + "\" y=\"22\" font-size=\"15\">" +
         xmlEscape(protocol.id) + ": mean preference with 95 % CI</text>\n";
  const int y0 = L.top, y1 = L.top + int(summary.items.size()) * L.rowHeight;
  for (int v = protocol.scale.min; v <= protocol.scale.max; ++v) {
    const int x = L.xOf(v, protocol.scale);
    svg += "<line x1=\"" + std::to_string(x) + "\" y1=\"" + std::to_string(y0) + "\" x2=\"" + std::to_string(x) +
           "\" y2=\"" + std::to_string(y1) + "\" stroke=\"" + (v == protocol.scale.midpoint() ? "#555555" : "#cccccc") +
           "\"/>\n";
    svg += "<text x=\"" + std::to_string(x) + "\" y=\"" + std::to_string(y1 + 18) + "\" text-anchor=\"middle\">" +
           std::to_string(v) + "</text>\n";
  }
  svg += "<text x=\"" + std::to_string(L.xOf(protocol.scale.min, protocol.scale)) + "\" y=\"" + std::to_string(y1 + 36) +
         "\">prefer " + xmlEscape(protocol.conditions[0].id) + "</text>\n";
  svg += "<text x=\"" + std::to_string(L.xOf(protocol.scale.max, protocol.scale)) + "\" y=\"" + std::to_string(y1 + 36) +
         "\" text-anchor=\"end\">prefer " + xmlEscape(protocol.conditions[1].id) + "</text>\n";
  for (std::size_t i = 0; i < summary.items.size(); ++i) {
    svg += "<text x=\"10\" y=\"" + std::to_string(L.top + int(i) * L.rowHeight + L.rowHeight / 2 + 4) + "\">" +
           xmlEscape(summary.items[i]) + "</text>\n";
    for (std::size_t c = 0; c < summary.columns.size(); ++c) {
      const SummaryCell& cell = summary.at(i, c);
      if (cell.stats.n == 0) continue;
      const int y = L.yOf(i, c, summary.columns.size());
      const std::string colour = hex(chartColumnColour(c));
      if (cell.stats.n > 1) {
        const double lo = std::clamp(cell.stats.ciLow, double(protocol.scale.min), double(protocol.scale.max));
        const double hi = std::clamp(cell.stats.ciHigh, double(protocol.scale.min), double(protocol.scale.max));
        svg += "<line x1=\"" + std::to_string(L.xOf(lo, protocol.scale)) + "\" y1=\"" + std::to_string(y) + "\" x2=\"" +
               std::to_string(L.xOf(hi, protocol.scale)) + "\" y2=\"" + std::to_string(y) + "\" stroke=\"" + colour +
               "\" stroke-width=\"3\"/>\n";
      }
      svg += "<rect x=\"" + std::to_string(L.xOf(cell.stats.mean, protocol.scale) - 5) + "\" y=\"" +
             std::to_string(y - 5) + "\" width=\"10\" height=\"10\" fill=\"" + colour + "\"><title>" +
             xmlEscape(cell.item + " / " + cell.group + ": mean " + number(cell.stats.mean, 2) + ", n " +
                       std::to_string(cell.stats.n)) +
             "</title></rect>\n";
    }
  }
  // Legend
  for (std::size_t c = 0; c < summary.columns.size(); ++c) {
    const int x = L.left + int(c) * 130;
    svg += "<rect x=\"" + std::to_string(x) + "\" y=\"" + std::to_string(H - 12) + "\" width=\"10\" height=\"10\" fill=\"" +
           hex(chartColumnColour(c)) + "\"/><text x=\"" + std::to_string(x + 14) + "\" y=\"" + std::to_string(H - 3) +
           "\">" + xmlEscape(summary.columns[c]) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace at::quiz
