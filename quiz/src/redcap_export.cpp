#include "quiz/redcap_export.h"

#include <cassert>
#include <map>

namespace at::quiz {

namespace {

// REDCap's data dictionary columns, in the order its upload expects.
const std::vector<std::string>& dictionaryHeader() {
  static const std::vector<std::string> header = {
      "Variable / Field Name", "Form Name", "Section Header", "Field Type", "Field Label",
      "Choices, Calculations, OR Slider Labels", "Field Note", "Text Validation Type OR Show Slider Number",
      "Text Validation Min", "Text Validation Max", "Identifier?", "Branching Logic (Show field only if...)",
      "Required Field?", "Custom Alignment", "Question Number (surveys only)", "Matrix Group Name",
      "Matrix Ranking?", "Field Annotation"};
  return header;
}

struct Field {
  std::string name, form, type, label, choices, note, validation, min, max;
  bool required = false;
};

// A choice label may hold commas (REDCap splits at the first one) but not the choice separator.
std::string choiceLabel(std::string text) {
  for (char& c : text)
    if (c == '|' || c == '\n' || c == '\r') c = '/';
  return text;
}

std::string codedChoices(const std::vector<std::string>& labels) {
  std::string s;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (i) s += " | ";
    s += std::to_string(i + 1) + ", " + choiceLabel(labels[i]);
  }
  return s;
}

// The paper's scale in words: 1 = strongly prefer condition 0 … midpoint = no preference …
// max = strongly prefer condition 1; points between say "somewhat", or their distance on longer scales.
std::string preferenceLabel(int value, const StudyProtocol& protocol) {
  const StudyScale& scale = protocol.scale;
  const int mid = scale.midpoint();
  const int distance = value < mid ? mid - value : value - mid;
  const int reach = value < mid ? mid - scale.min : scale.max - mid;
  if (distance == 0) return "no preference";
  const std::string condition = value < mid ? protocol.conditions[0].id : protocol.conditions[1].id;
  if (distance == reach) return "strongly prefer " + condition;
  if (reach == 2) return "somewhat prefer " + condition;
  return "prefer " + condition + " (" + std::to_string(distance) + " of " + std::to_string(reach) + ")";
}

std::string scaleChoices(const StudyProtocol& protocol, bool asShown) {
  std::string s;
  for (int v = protocol.scale.min; v <= protocol.scale.max; ++v) {
    if (v > protocol.scale.min) s += " | ";
    std::string label;
    if (asShown) {
      auto anchor = protocol.scale.anchors.find(v);
      label = anchor != protocol.scale.anchors.end() ? anchor->second : std::to_string(v) + " (between anchors)";
    } else {
      label = preferenceLabel(v, protocol);
    }
    s += std::to_string(v) + ", " + choiceLabel(label);
  }
  return s;
}

std::vector<Field> fields(const StudyProtocol& protocol) {
  std::vector<std::string> conditions, items;
  for (const auto& c : protocol.conditions) conditions.push_back(c.id + " - " + c.label);
  for (const auto& it : protocol.items) items.push_back(it.id + " - " + it.wording);
  const std::string P = kRedcapParticipantForm, R = kRedcapRatingForm;
  const std::string structures = std::to_string(protocol.structures.size());
  return {
      {"participant_id", P, "text", "Participant ID (pseudonymous)", "", "", "", "", "", true},
      {"participant_group", P, "dropdown", "Participant group", codedChoices(protocol.groups), "", "", "", "", true},
      {"enrolment_index", P, "text", "Enrolment order (0-based; selects the counterbalancing row)", "", "", "integer",
       "0", ""},
      {"sessions", P, "text", "Sessions the participant started", "", "", "integer", "1", ""},
      {"finished_study", P, "yesno", "Rated every structure (No: partial data)", "", "", "", "", ""},
      {"structure", R, "dropdown", "Structure rated", codedChoices(protocol.structures), "", "", "", "", true},
      {"item", R, "dropdown", "Questionnaire item", codedChoices(items), "", "", "", "", true},
      {"rating_ab", R, "radio", "Rating as shown to the participant (A/B)", scaleChoices(protocol, true), "", "", "",
       "", true},
      {"rating", R, "radio", "Rating unblinded: " + protocol.conditions[0].id + " vs " + protocol.conditions[1].id,
       scaleChoices(protocol, false), "", "", "", "", true},
      {"a_condition", R, "dropdown", "Condition shown as A (the other was B)", codedChoices(conditions), "", "", "", "",
       true},
      {"presentation_order", R, "text", "Position of the structure in the participant's sequence", "", "", "integer",
       "1", structures},
      {"session", R, "text", "The participant's session in which the item was rated", "", "blank: not known",
       "integer", "1", ""},
      {"preset_a", R, "text", "Preset shown as A", "", "", "", "", ""},
      {"preset_b", R, "text", "Preset shown as B", "", "", "", "", ""},
      {"t", R, "text", "Blend t between data and distance transfer functions", "", "", "number", "0", "1"},
      {"alpha", R, "text", "Distance normalisation alpha", "", "", "number", "", ""},
      {"beta", R, "text", "Distance lighting beta", "", "", "number", "", ""},
      {"view_ms_a", R, "text", "Time view A was on screen (ms)", "", "blank: shown as files, not measured", "number",
       "0", ""},
      {"view_ms_b", R, "text", "Time view B was on screen (ms)", "", "blank: shown as files, not measured", "number",
       "0", ""},
      {"toggles", R, "text", "A/B toggles", "", "blank: not measured", "integer", "0", ""},
      {"response_ms", R, "text", "Time from showing the item to the rating (ms)", "", "", "number", "0", ""},
      {"rated_at", R, "text", "When the rating was recorded (UTC)", "", "", "datetime_seconds_ymd", "", ""},
      {"app_version", R, "text", "Anatomy Tutor version", "", "", "", "", ""},
      {"comment", R, "notes", "Participant's comment on the structure", "", "", "", "", ""},
  };
}

// "2026-11-22T05:01:02Z" (or with fractions) → "2026-11-22 05:01:02", REDCap's Y-M-D H:M:S.
std::string redcapDateTime(const std::string& iso) {
  if (iso.size() < 19) return "";
  std::string s = iso.substr(0, 19);
  if (s[10] == 'T') s[10] = ' ';
  return s;
}

std::string codeOf(const std::string& value, const std::vector<std::string>& values) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (values[i] == value) return std::to_string(i + 1);
  return "";
}

}  // namespace

std::string redcapDictionaryCsv(const StudyProtocol& protocol) {
  std::vector<std::string> header;
  for (const std::string& h : dictionaryHeader()) header.push_back(csvQuoted(h));
  std::string out = csvRecord(header);
  for (const Field& f : fields(protocol))
    out += csvRecord({f.name, f.form, "", f.type, csvQuoted(f.label), csvQuoted(f.choices), csvQuoted(f.note),
                      f.validation, f.min, f.max, "", "", f.required ? "y" : "", "", "", "", "", ""});
  return out;
}

std::string redcapRecordsCsv(const StudyProtocol& protocol, const std::vector<StudyParticipantRow>& participants,
                             const std::vector<StudyResponseRow>& rows) {
  const std::vector<Field> all = fields(protocol);
  // Columns: the record id, the two repeat columns, then each form's fields followed by its
  // completion status (REDCap's <form>_complete: 2 = Complete), as REDCap's own export orders them.
  std::vector<std::string> header = {all[0].name, "redcap_repeat_instrument", "redcap_repeat_instance"};
  for (std::size_t i = 1; i < all.size(); ++i) {
    header.push_back(all[i].name);
    if (i + 1 == all.size() || all[i + 1].form != all[i].form) header.push_back(all[i].form + "_complete");
  }
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  std::vector<std::string> itemIds, conditionIds;
  for (const auto& it : protocol.items) itemIds.push_back(it.id);
  for (const auto& c : protocol.conditions) conditionIds.push_back(c.id);

  std::map<std::string, std::vector<const StudyResponseRow*>> byParticipant;
  for (const StudyResponseRow& r : rows) byParticipant[r.participantId].push_back(&r);

  std::string out = csvRecord(header);
  for (const StudyParticipantRow& p : participants) {
    std::vector<std::string> record(header.size());
    auto set = [&](const std::string& name, const std::string& value) { record[column.at(name)] = value; };
    set("participant_id", csvQuoted(p.participantId));
    set("participant_group", codeOf(p.group, protocol.groups));
    set("enrolment_index", std::to_string(p.enrolmentIndex));
    set("sessions", std::to_string(p.sessions));
    set("finished_study", p.complete ? "1" : "0");
    set(std::string(kRedcapParticipantForm) + "_complete", p.complete ? "2" : "1");
    out += csvRecord(record);

    int instance = 0;
    for (const StudyResponseRow* r : byParticipant[p.participantId]) {
      std::fill(record.begin(), record.end(), std::string());
      set("participant_id", csvQuoted(p.participantId));
      set("redcap_repeat_instrument", kRedcapRatingForm);
      set("redcap_repeat_instance", std::to_string(++instance));
      set("structure", codeOf(r->structure, protocol.structures));
      set("item", codeOf(r->item, itemIds));
      set("rating_ab", std::to_string(r->ratingAb));
      set("rating", std::to_string(r->rating));
      set("a_condition", codeOf(r->aCondition, conditionIds));
      set("presentation_order", std::to_string(r->presentationOrder));
      set("session", r->session > 0 ? std::to_string(r->session) : "");
      set("preset_a", csvQuoted(r->presetA));
      set("preset_b", csvQuoted(r->presetB));
      set("t", csvNumber(r->t));
      set("alpha", csvNumber(r->alpha));
      set("beta", csvNumber(r->beta));
      if (r->viewingMeasured) {
        set("view_ms_a", csvNumber(r->viewMsA, 0));
        set("view_ms_b", csvNumber(r->viewMsB, 0));
        set("toggles", std::to_string(r->toggles));
      }
      set("response_ms", csvNumber(r->responseMs, 0));
      set("rated_at", redcapDateTime(r->timestampUtc));
      set("app_version", csvQuoted(r->appVersion));
      set("comment", csvQuoted(r->comment));
      set(std::string(kRedcapRatingForm) + "_complete", "2");
      out += csvRecord(record);
    }
    byParticipant.erase(p.participantId);
  }
  assert(byParticipant.empty() && "rows of a participant missing from the participant list");
  return out;
}

std::string redcapRepeatingFormsCsv() {
  return csvRecord({"form_name", "custom_form_label"}) + csvRecord({kRedcapRatingForm, csvQuoted("[structure], [item]")});
}

}  // namespace at::quiz
