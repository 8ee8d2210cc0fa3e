// The UI script's expert-panel actions: the transfer functions' points and the preset's parameters,
// through the TfEditor commands the panel's widgets call. Each opens the expert panel when closed.
#include "script/script_answers.h"
#include "script/script_interpreter.h"

namespace at::app {

using json = nlohmann::json;

ScriptInterpreter::Feature ScriptInterpreter::expertActions() {
  using S = ScriptInterpreter;
  const ScriptArgument tf{"tf", "\"data\" (over the values) or \"distance\" (over the distance)"};
  const ScriptArgument index{"index", "the point's index"};
  const ScriptArgument rgba{"rgba?", "[r, g, b, a], 0..1"};
  return {"expert",
          "the expert panel: transfer functions and presets",
          {
              {"expert", {{"on?", "true (default) opens, false closes"}}, "Opens or closes the expert panel.", &S::expert},
              {"tf_add_point", {tf, {"x", "the value (or distance) of the point"}, rgba}, "Adds a point to the transfer function.",
               &S::tfEdit},
              {"tf_move_point", {tf, index, {"x?", "its new position"}, {"alpha?", "its new opacity"}},
               "Moves a transfer-function point.", &S::tfEdit},
              {"tf_delete_point", {tf, index}, "Deletes a transfer-function point.", &S::tfEdit},
              {"tf_colour", {tf, index, rgba}, "Sets a transfer-function point's colour.", &S::tfEdit},
              {"preset_set",
               {{"mode?", "wdt, bare, unweighted, fuzzy, outline or lighting"}, {"t?", "the blend t"}, {"alpha?", "opacity"},
                {"lighting_alpha?", "the lighting's alpha"}, {"lighting_beta?", "the lighting's beta"},
                {"rule?", "the WDT's step rule: entering or trapezoid"}, {"base?", "the weight base"},
                {"hu_window?", "[low, high] HU"}},
               "Sets the preset's parameters that are given; a new mode first loads that mode's preset (as the panel's mode list does).",
               &S::presetSet},
              {"preset_save", {{"name", "the preset's name"}, {"export?", "also write it to this JSON file"}},
               "Saves the preset into the database (and exports it).", &S::presetSave},
          }};
}

ScriptInterpreter::Outcome ScriptInterpreter::expert(Context& c) {
  c.model.setExpert(c.action.value("on", true));
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::tfEdit(Context& c) {
  if (!c.model.expertOn()) c.model.setExpert(true);
  TfEditor& e = c.model.expert();
  const std::string what = c.action.at("do");
  const std::string tf = c.action.value("tf", "");
  if (tf != "data" && tf != "distance") return actionError(c.action, Error{ErrorKind::Invalid, "\"tf\" must be \"data\" or \"distance\", got \"" + tf + "\""});
  const bool data = tf == "data";
  const auto rgba = [&]() -> std::optional<render::Rgba> {
    if (!c.action.contains("rgba")) return std::nullopt;
    const auto v = c.action.at("rgba").get<std::vector<float>>();
    if (v.size() != 4) throw std::invalid_argument("\"rgba\" must be 4 numbers");
    return render::Rgba{v[0], v[1], v[2], v[3]};
  };
  Status st;
  if (what == "tf_add_point") {
    auto i = e.addPoint(data, c.action.at("x").get<double>(), rgba());
    if (!i) st = tl::unexpected(i.error());
  } else {
    const std::size_t index = c.action.at("index").get<std::size_t>();
    const auto& pts = data ? e.preset().dataTf : e.preset().distanceTf;
    if (what != "tf_delete_point" && index >= pts.size()) return actionError(c.action, Error{ErrorKind::Invalid, "no point " + std::to_string(index)});
    if (what == "tf_move_point")
      st = e.movePoint(data, index, c.action.value("x", pts[index].x), c.action.value("alpha", pts[index].rgba[3]));
    else if (what == "tf_delete_point")
      st = e.deletePoint(data, index);
    else
      st = e.setColour(data, index, rgba().value_or(pts[index].rgba));
  }
  if (!st) return actionError(c.action, st.error());
  c.model.expertEdited();
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::presetSet(Context& c) {
  if (!c.model.expertOn()) c.model.setExpert(true);
  const json& a = c.action;
  if (a.contains("mode")) {  // as the panel's mode list: the mode's own preset, then the rest given
    auto m = render::parseRenderMode(a.at("mode").get<std::string>());
    if (!m) return actionError(a, m.error());
    c.model.expert().switchMode(*m);
  }
  render::Preset p = c.model.expert().preset();
  p.t = a.value("t", p.t);
  p.alpha = a.value("alpha", p.alpha);
  p.lightingAlpha = a.value("lighting_alpha", p.lightingAlpha);
  p.lightingBeta = a.value("lighting_beta", p.lightingBeta);
  p.weightRule = a.value("rule", p.weightRule);
  p.weightBase = a.value("base", p.weightBase);
  if (a.contains("hu_window")) p.huWindow = a.at("hu_window").get<std::array<float, 2>>();
  if (auto st = c.model.expert().setParameters(p); !st) return actionError(a, st.error());
  c.model.expertEdited();
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::presetSave(Context& c) {
  if (!c.model.expertOn()) c.model.setExpert(true);
  const json& a = c.action;
  auto st = c.model.expert().saveAs(a.at("name").get<std::string>(), a.contains("export")
                                                                          ? std::optional<std::string>(a.at("export").get<std::string>())
                                                                          : std::nullopt);
  if (!st) return actionError(a, st.error());
  return Progress::Done;
}

}  // namespace at::app
