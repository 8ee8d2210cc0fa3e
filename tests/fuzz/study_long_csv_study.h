// The study fuzz_study_long_csv reads long tables against, and at_fuzz_seeds writes its seeds for.
#pragma once

namespace at::fuzz {

inline constexpr const char* kLongCsvStudy = R"({
  "id": "s1", "title": "Fuzz study", "dataset": "phantom",
  "structures": ["cochlea", "stapes", "incus"],
  "conditions": [{"id": "wdt", "label": "WDT", "preset_suffix": "_wdt"},
                 {"id": "bare", "label": "Bare", "preset_suffix": "_bare"}],
  "items": [{"id": "shape", "wording": "Shape?"}, {"id": "context", "wording": "Context?"}],
  "scale": {"min": 1, "max": 5, "anchors": {"1": "A much better", "5": "B much better"}},
  "groups": ["non-medical", "medical"], "seed": 9 })";

}  // namespace at::fuzz
