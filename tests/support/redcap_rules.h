// REDCap's documented import rules, as a checker for the files a study export writes: the data
// dictionary (Project Setup → Data Dictionary upload), the records (Data Import Tool, CSV) and the
// repeating-instruments setting (Project Setup → Repeating instruments, CSV upload). It returns the
// problems REDCap would refuse or silently mangle, one line each; empty when the files import.
//
// The rules, from REDCap's data dictionary and data import documentation:
//  dictionary
//   - the 18 columns, in order, with REDCap's headers;
//   - variable names: lowercase letters, digits and underscores, starting with a letter, unique;
//     at most 26 characters (REDCap's recommendation; exports to SAS/SPSS/Stata cut longer names);
//     not a name REDCap reserves (redcap_*, names of its own record and event parameters) and not
//     <form>_complete (the form status field REDCap adds to every instrument);
//   - form names: the same characters; the fields of one form are contiguous;
//   - the first field is the record id (on the first form);
//   - field types from REDCap's list; every field has a label;
//   - dropdown/radio/checkbox: "code, label | code, label", codes numbers or letters, digits and
//     underscores, unique, labels not empty; other types have no choices (except calc/slider);
//   - text validation from REDCap's list, only on text fields; min/max are numbers (or dates for
//     date validations);
//   - Identifier? and Required Field? are "y" or blank;
//  repeating instruments: header form_name,custom_form_label; each form exists and is not the
//   record id's form;
//  records
//   - the first column is the record id field; redcap_repeat_instrument and redcap_repeat_instance
//     follow it when the project repeats; every other column is a dictionary field or a form's
//     <form>_complete;
//   - every row has as many cells as the header and a record id;
//   - a row with a blank repeat instrument fills only fields of non-repeating forms and has a blank
//     instance; a repeating row names a repeating form, has a positive integer instance, fills only
//     that form's fields and is the only row for (record, form, instance);
//   - values: choice fields hold one of their codes; yesno 0/1; truefalse 0/1; <form>_complete
//     0/1/2; integer validation an integer in range; number a decimal number in range (dot
//     decimal separator); datetime_seconds_ymd "YYYY-MM-DD HH:MM:SS"; date_ymd "YYYY-MM-DD".
#pragma once

#include <algorithm>
#include <cstdlib>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "quiz/study_report.h"

namespace at::test {

struct RedcapField {
  std::string name, form, type, label, validation, min, max;
  std::vector<std::string> codes;
};

inline std::vector<std::string> redcapDictionaryHeader() {
  return {"Variable / Field Name", "Form Name", "Section Header", "Field Type", "Field Label",
          "Choices, Calculations, OR Slider Labels", "Field Note", "Text Validation Type OR Show Slider Number",
          "Text Validation Min", "Text Validation Max", "Identifier?", "Branching Logic (Show field only if...)",
          "Required Field?", "Custom Alignment", "Question Number (surveys only)", "Matrix Group Name",
          "Matrix Ranking?", "Field Annotation"};
}

inline bool redcapName(const std::string& s) { return std::regex_match(s, std::regex("[a-z][a-z0-9_]*")); }

inline bool redcapInteger(const std::string& s) { return std::regex_match(s, std::regex("-?[0-9]+")); }
inline bool redcapNumber(const std::string& s) {
  return std::regex_match(s, std::regex("-?([0-9]+(\\.[0-9]*)?|\\.[0-9]+)"));
}

// Parses the dictionary; problems are appended to `problems`.
inline std::vector<RedcapField> readRedcapDictionary(const std::string& csv, std::vector<std::string>& problems) {
  static const std::set<std::string> types = {"text", "notes", "dropdown", "radio", "checkbox", "yesno", "truefalse",
                                              "calc", "file", "slider", "descriptive", "sql"};
  static const std::set<std::string> validations = {
      "", "date_ymd", "date_mdy", "date_dmy", "datetime_ymd", "datetime_mdy", "datetime_dmy", "datetime_seconds_ymd",
      "datetime_seconds_mdy", "datetime_seconds_dmy", "time", "time_mm_ss", "integer", "number", "number_1dp",
      "number_2dp", "email", "phone", "zipcode", "alpha_only", "mrn_10d"};
  static const std::set<std::string> reserved = {"record", "event", "event_id", "arm", "instance", "page", "pid",
                                                 "hidden_edit_flag", "submit_action", "new_form"};
  std::vector<RedcapField> fields;
  const auto rows = quiz::parseCsv(csv);
  if (rows.empty() || rows[0] != redcapDictionaryHeader()) {
    problems.push_back("dictionary: the header is not REDCap's 18 columns");
    return fields;
  }
  std::set<std::string> names, formsSeen;
  std::string previousForm;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    const std::string where = "dictionary row " + std::to_string(i + 1);
    if (r.size() != 18) {
      problems.push_back(where + ": " + std::to_string(r.size()) + " cells, not 18");
      continue;
    }
    RedcapField f{r[0], r[1], r[3], r[4], r[7], r[8], r[9], {}};
    if (!redcapName(f.name)) problems.push_back(where + ": variable name '" + f.name + "' has invalid characters");
    if (f.name.size() > 26) problems.push_back(where + ": variable name '" + f.name + "' is over 26 characters");
    if (!names.insert(f.name).second) problems.push_back(where + ": variable name '" + f.name + "' repeats");
    if (f.name.rfind("redcap_", 0) == 0 || reserved.count(f.name))
      problems.push_back(where + ": variable name '" + f.name + "' is reserved by REDCap");
    if (!redcapName(f.form)) problems.push_back(where + ": form name '" + f.form + "' has invalid characters");
    if (f.form != previousForm) {
      if (!formsSeen.insert(f.form).second) problems.push_back(where + ": form '" + f.form + "' is not contiguous");
      previousForm = f.form;
    }
    if (!types.count(f.type)) problems.push_back(where + ": field type '" + f.type + "' is not REDCap's");
    if (f.label.empty()) problems.push_back(where + ": field '" + f.name + "' has no label");
    const std::string& choices = r[5];
    if (f.type == "dropdown" || f.type == "radio" || f.type == "checkbox") {
      std::set<std::string> codes;
      std::size_t start = 0;
      while (start <= choices.size()) {
        std::size_t bar = choices.find('|', start);
        if (bar == std::string::npos) bar = choices.size();
        std::string choice = choices.substr(start, bar - start);
        const auto first = choice.find_first_not_of(' '), last = choice.find_last_not_of(' ');
        choice = first == std::string::npos ? "" : choice.substr(first, last - first + 1);
        const auto comma = choice.find(',');
        const std::string code = comma == std::string::npos ? "" : choice.substr(0, comma);
        const std::string label = comma == std::string::npos ? "" : choice.substr(comma + 1);
        if (!std::regex_match(code, std::regex("-?[0-9]+(\\.[0-9]+)?|[A-Za-z0-9_]+")))
          problems.push_back(where + ": choice '" + choice + "' of '" + f.name + "' has no valid code");
        else if (!codes.insert(code).second)
          problems.push_back(where + ": choice code '" + code + "' of '" + f.name + "' repeats");
        if (label.find_first_not_of(' ') == std::string::npos)
          problems.push_back(where + ": choice '" + code + "' of '" + f.name + "' has no label");
        f.codes.push_back(code);
        start = bar + 1;
      }
    } else if (!choices.empty() && f.type != "calc" && f.type != "slider") {
      problems.push_back(where + ": field '" + f.name + "' of type " + f.type + " has choices");
    }
    if (!validations.count(f.validation)) problems.push_back(where + ": validation '" + f.validation + "' unknown");
    if (!f.validation.empty() && f.type != "text")
      problems.push_back(where + ": validation on a " + f.type + " field");
    for (const std::string& bound : {f.min, f.max})
      if (!bound.empty() && (f.validation == "integer" || f.validation == "number") && !redcapNumber(bound))
        problems.push_back(where + ": bound '" + bound + "' of '" + f.name + "' is not a number");
    if (!r[10].empty() && r[10] != "y") problems.push_back(where + ": Identifier? must be y or blank");
    if (!r[12].empty() && r[12] != "y") problems.push_back(where + ": Required Field? must be y or blank");
    fields.push_back(f);
  }
  for (const auto& f : fields)
    for (const std::string& form : formsSeen)
      if (f.name == form + "_complete")
        problems.push_back("dictionary: '" + f.name + "' clashes with REDCap's status field of form '" + form + "'");
  if (fields.empty()) problems.push_back("dictionary: no fields");
  return fields;
}

// Every rule above, for one export; returns the problems found.
inline std::vector<std::string> checkRedcapImport(const std::string& dictionaryCsv, const std::string& recordsCsv,
                                                  const std::string& repeatingCsv) {
  std::vector<std::string> problems;
  const std::vector<RedcapField> fields = readRedcapDictionary(dictionaryCsv, problems);
  if (fields.empty()) return problems;
  std::map<std::string, const RedcapField*> byName;
  std::set<std::string> forms;
  for (const auto& f : fields) {
    byName[f.name] = &f;
    forms.insert(f.form);
  }
  const RedcapField& recordId = fields.front();

  std::set<std::string> repeating;
  const auto rep = quiz::parseCsv(repeatingCsv);
  if (rep.empty() || rep[0] != std::vector<std::string>{"form_name", "custom_form_label"}) {
    problems.push_back("repeating forms: header is not form_name,custom_form_label");
  } else {
    for (std::size_t i = 1; i < rep.size(); ++i) {
      if (rep[i].size() != 2 || !forms.count(rep[i][0])) {
        problems.push_back("repeating forms row " + std::to_string(i + 1) + ": not a form of the dictionary");
        continue;
      }
      if (rep[i][0] == recordId.form) problems.push_back("repeating forms: the record id's form cannot repeat");
      repeating.insert(rep[i][0]);
    }
  }

  const auto rows = quiz::parseCsv(recordsCsv);
  if (rows.empty()) {
    problems.push_back("records: empty file");
    return problems;
  }
  const auto& header = rows[0];
  if (header.empty() || header[0] != recordId.name)
    problems.push_back("records: the first column is not the record id field '" + recordId.name + "'");
  const bool repeats = header.size() >= 3 && header[1] == "redcap_repeat_instrument" &&
                       header[2] == "redcap_repeat_instance";
  if (!repeating.empty() && !repeats)
    problems.push_back("records: repeating forms but no redcap_repeat_instrument/redcap_repeat_instance columns");
  std::set<std::string> seenColumns;
  for (std::size_t c = 0; c < header.size(); ++c) {
    const std::string& h = header[c];
    if (!seenColumns.insert(h).second) problems.push_back("records: column '" + h + "' repeats");
    if (repeats && (c == 1 || c == 2)) continue;
    const bool status = h.size() > 9 && h.substr(h.size() - 9) == "_complete" && forms.count(h.substr(0, h.size() - 9));
    if (!byName.count(h) && !status) problems.push_back("records: column '" + h + "' is not a field of the dictionary");
  }
  auto formOf = [&](const std::string& column) -> std::string {
    if (auto it = byName.find(column); it != byName.end()) return it->second->form;
    return column.size() > 9 ? column.substr(0, column.size() - 9) : "";
  };
  std::set<std::tuple<std::string, std::string, std::string>> instances;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    const std::string where = "records row " + std::to_string(i + 1);
    if (r.size() != header.size()) {
      problems.push_back(where + ": " + std::to_string(r.size()) + " cells, header has " + std::to_string(header.size()));
      continue;
    }
    if (r[0].empty()) problems.push_back(where + ": no record id");
    std::string instrument, instance;
    if (repeats) {
      instrument = r[1];
      instance = r[2];
      if (instrument.empty() && !instance.empty()) problems.push_back(where + ": an instance without an instrument");
      if (!instrument.empty()) {
        if (!repeating.count(instrument)) problems.push_back(where + ": '" + instrument + "' is not a repeating form");
        if (!redcapInteger(instance) || std::atoi(instance.c_str()) < 1)
          problems.push_back(where + ": instance '" + instance + "' is not a positive integer");
        if (!instances.insert({r[0], instrument, instance}).second)
          problems.push_back(where + ": record " + r[0] + " has instance " + instance + " of " + instrument + " twice");
      }
    }
    for (std::size_t c = 1; c < header.size(); ++c) {
      if (repeats && (c == 1 || c == 2)) continue;
      const std::string& v = r[c];
      if (v.empty()) continue;
      const std::string& column = header[c];
      const std::string form = formOf(column);
      if (instrument.empty() ? repeating.count(form) != 0 : form != instrument)
        problems.push_back(where + ": '" + column + "' (form " + form + ") is filled on a row of " +
                           (instrument.empty() ? std::string("the record's non-repeating forms") : instrument));
      const std::string what = where + ": '" + column + "' = '" + v + "'";
      auto it = byName.find(column);
      if (it == byName.end()) {  // a form status
        if (v != "0" && v != "1" && v != "2") problems.push_back(what + " is not a form status 0/1/2");
        continue;
      }
      const RedcapField& f = *it->second;
      if (!f.codes.empty()) {
        if (std::find(f.codes.begin(), f.codes.end(), v) == f.codes.end())
          problems.push_back(what + " is not one of its choice codes");
      } else if (f.type == "yesno" || f.type == "truefalse") {
        if (v != "0" && v != "1") problems.push_back(what + " is not 0 or 1");
      } else if (f.validation == "integer" || f.validation == "number") {
        const bool ok = f.validation == "integer" ? redcapInteger(v) : redcapNumber(v);
        if (!ok) {
          problems.push_back(what + " is not " + (f.validation == "integer" ? "an integer" : "a number"));
        } else {
          const double x = std::strtod(v.c_str(), nullptr);
          if (!f.min.empty() && x < std::strtod(f.min.c_str(), nullptr)) problems.push_back(what + " is below " + f.min);
          if (!f.max.empty() && x > std::strtod(f.max.c_str(), nullptr)) problems.push_back(what + " is above " + f.max);
        }
      } else if (f.validation == "datetime_seconds_ymd") {
        if (!std::regex_match(v, std::regex("[0-9]{4}-[0-9]{2}-[0-9]{2} [0-9]{2}:[0-9]{2}:[0-9]{2}")))
          problems.push_back(what + " is not YYYY-MM-DD HH:MM:SS");
      } else if (f.validation == "date_ymd") {
        if (!std::regex_match(v, std::regex("[0-9]{4}-[0-9]{2}-[0-9]{2}"))) problems.push_back(what + " is not YYYY-MM-DD");
      }
    }
  }
  return problems;
}

}  // namespace at::test
