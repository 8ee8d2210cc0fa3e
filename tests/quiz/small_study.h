// A two-structure, two-item study for the quiz tests of study exports (study_report, the long
// table's reader).
#pragma once

#include <doctest/doctest.h>

#include "quiz/study_protocol.h"

namespace at::test {

inline quiz::StudyProtocol smallStudyProtocol() {
  auto p = quiz::parseStudyProtocol(R"({
    "id": "s1", "title": "Small study", "dataset": "phantom",
    "structures": ["cochlea", "stapes"],
    "conditions": [{"id": "wdt", "label": "WDT", "preset_suffix": "_wdt"},
                   {"id": "bare", "label": "Bare", "preset_suffix": "_bare"}],
    "items": [{"id": "shape", "wording": "Shape?"}, {"id": "context", "wording": "Context?"}],
    "scale": {"min": 1, "max": 5, "anchors": {"1": "A much better", "5": "B much better"}},
    "groups": ["non-medical", "medical"], "seed": 9 })", "small.json");
  REQUIRE(p.has_value());
  return *p;
}

}  // namespace at::test
