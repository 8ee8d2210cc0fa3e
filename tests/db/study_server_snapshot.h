// Shared by the study-server tests: the paper's survey protocol, and every row of the study tables
// and of the audit as one text (a refused write must leave it byte-identical).
#pragma once

#include <doctest/doctest.h>

#include <string>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "quiz/study_protocol.h"
#include "test_support.h"

namespace at::test {

inline quiz::StudyProtocol paperSurvey() {
  auto p = quiz::loadStudyProtocol((sourceDir() / "data/studies/paper_survey.json").string());
  REQUIRE(p.has_value());
  return *p;
}

// Every row of the study tables and of the audit, as the administrator reads them: one text.
inline std::string studySnapshot(db::Database& admin) {
  std::string out;
  for (const char* table : {"studies", "study_participants", "study_trials", "study_ratings", "class_audit"}) {
    auto s = admin.prepare(std::string("SELECT coalesce(string_agg(t::text, E'\\n' ORDER BY t::text), '') FROM ") + table + " t");
    REQUIRE(s);
    REQUIRE(*s->step());
    out += std::string(table) + ":\n" + s->text(0) + "\n";
  }
  return out;
}

}  // namespace at::test
