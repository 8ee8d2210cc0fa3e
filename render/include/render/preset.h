// Rendering presets (ARCHITECTURE.md §8): JSON files an expert writes and students load.
//
//   { "schema": 1, "name": "…", "mode": "wdt",
//     "data_tf": [ {"x": HU, "rgba": [r,g,b,a]}, … ], "distance_tf": [ {"x": 0..1, "rgba": […]}, … ],
//     "alpha": 1.6, "t": 0.5, "highlight_rgb": [1,0.5,0], "lighting": {"alpha": 0.1, "beta": 1.0},
//     "weight": {"rule": "entering", "hu_window": [-1000, 2000], "base": 0.02},
//     "structure_opacity": 0.9, "context_in_front": 0.4, "surface": {"gradient_hu": [40, 300], "interior": 0},
//     "id": "…", "structure": "cochlea", "view": "lateral_left", "clip": [nx, ny, nz, d] }
//
// Loading is strict: an unknown field, a wrong type or an out-of-range value is an error naming the
// field ("cochlea_wdt.json: field 'data_tf[2].rgba' must be 4 numbers in 0..1"). Missing fields take
// the defaults of `Preset` below (documented there). Colours are sRGB display values 0..1.
// Saving writes every field, so load → save → load gives an equal Preset.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "render/transfer_function.h"
#include "core/error.h"

namespace at::render {

// wdt: WDT context (Figs. 1, 2); bare: only the structure (the study's baseline); unweighted: the
// wdt look on a field computed with uniform weights (Fig. 4); fuzzy: Eqs. 4–5 (Fig. 5); outline:
// a distance TF peaking away from the structure (Fig. 6); lighting: Eq. 6 (Fig. 7).
enum class RenderMode { Wdt, Bare, Unweighted, Fuzzy, Outline, Lighting };
const char* toString(RenderMode mode);
Result<RenderMode> parseRenderMode(const std::string& text);
const std::vector<RenderMode>& allRenderModes();

struct Preset {
  int schema = 1;                 // only 1 exists
  std::string name = "Untitled";
  RenderMode mode = RenderMode::Wdt;
  // Default data TF: air and fat clear, soft tissue faint, bone white and fairly opaque.
  std::vector<TfPoint> dataTf{{-1000, {0, 0, 0, 0}}, {-100, {0, 0, 0, 0}}, {60, {0.8f, 0.55f, 0.45f, 0.05f}},
                              {400, {0.95f, 0.9f, 0.8f, 0.3f}}, {2000, {1, 1, 1, 0.8f}}};
  // Default distance TF: structure colour at the structure, fading out by half the normalised range.
  std::vector<TfPoint> distanceTf{{0, {1, 1, 1, 0}}, {0.5, {1, 0.9f, 0.6f, 0.2f}}, {1, {1, 0.5f, 0, 1}}};
  float alpha = 1.6f;             // f(x) = 2 / (1 + alpha^x); > 1
  float t = 0.5f;                 // context blend 0..1 (Algorithm 1)
  std::array<float, 3> highlightRgb{1, 0.5f, 0};  // bare-mode colour; lighting colour
  float lightingAlpha = 0.1f;     // Eq. 6: k_a = beta / (alpha·D + 1)²; ≥ 0
  float lightingBeta = 1.0f;      // ≥ 0
  std::string weightRule = "entering";  // step rule of the WDT: entering | trapezoid
  std::array<float, 2> huWindow{-1000, 2000};
  float weightBase = 0.02f;       // ≥ 0
  // The selected structure's surface opacity in the context modes (bare draws it opaque), 0..1.
  float structureOpacity = 0.9f;
  // Context between the eye and the structure is drawn at this share of its opacity (1: as the
  // TFs say), so that medium-opacity bone in front does not veil the structure the user looks at.
  float contextInFront = 0.4f;
  // Context surfaces (render_settings.h): the table's opacity is scaled by
  // lerp(surfaceInterior, 1, smoothstep(lo, hi, g)) for edge strength g in HU per voxel of the
  // smoothed volume. interior = 1 and lo = hi = 0 give the unmodulated Algorithm 1.
  std::array<float, 2> surfaceGradientHu{40, 300};  // lo ≤ hi, ≥ 0
  float surfaceInterior = 0;      // 0..1
  std::optional<std::string> id;         // defaults to the file's stem when loaded from a file
  std::optional<std::string> structure;  // structure id the preset was made for
  std::optional<std::string> view;       // named view (camera.h)
  std::optional<std::array<float, 4>> clip;  // plane nx, ny, nz, d (mm, LPS)

  bool operator==(const Preset&) const = default;
};

// `source` names the text in error messages (a file name).
Result<Preset> parsePreset(const std::string& jsonText, const std::string& source);
Result<Preset> loadPreset(const std::filesystem::path& path);
std::string presetToJson(const Preset& preset);  // pretty-printed, every field written
Status savePreset(const Preset& preset, const std::filesystem::path& path);

// The presets of one folder (data/presets). Ids are file stems ("cochlea_wdt").
class PresetLibrary {
 public:
  explicit PresetLibrary(std::filesystem::path dir) : dir_(std::move(dir)) {}
  const std::filesystem::path& dir() const { return dir_; }
  // Sorted ids of every *.json in the folder; error if the folder cannot be read.
  Result<std::vector<std::string>> list() const;
  Result<Preset> load(const std::string& id) const;
  // The shipped preset for a structure and mode: "<structure>_<mode>", else "default_<mode>".
  Result<Preset> forStructure(const std::string& structureId, RenderMode mode) const;

 private:
  std::filesystem::path dir_;
};

}  // namespace at::render
