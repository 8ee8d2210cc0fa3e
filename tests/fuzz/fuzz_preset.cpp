// Render presets (JSON, schema 1) through parsePreset; a preset that parses must survive its own
// round trip through presetToJson.
#include "fuzz_support.h"
#include "render/preset.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto preset = render::parsePreset(text, "preset.json");
  fuzz::checkResult(preset, "preset.json");
  if (!preset) return 0;
  auto again = render::parsePreset(render::presetToJson(*preset), "again.json");
  fuzz::expect(bool(again), "a parsed preset's JSON parses again");
  return 0;
}
