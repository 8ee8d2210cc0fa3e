// The UI script's actions on the 3-D view: what a pointer and the explore panel do (select, hover,
// click, orbit, zoom, clip, the blend t and the render mode).
#include "script/script_answers.h"
#include "script/script_interpreter.h"

#include "render/camera.h"

namespace at::app {

using json = nlohmann::json;

namespace {
// The structure named by the action's "structure" (its id or name) in the dataset on screen.
Result<const Structure*> structureArg(const DesktopModel& model, const json& a) {
  const std::string id = a.value("structure", "");
  const Structure* s = model.dataset().findStructure(id);
  if (!s) return fail("ui script: no structure '" + id + "' in dataset '" + model.dataset().id + "'");
  return s;
}
}  // namespace

ScriptInterpreter::Feature ScriptInterpreter::viewActions() {
  using S = ScriptInterpreter;
  const ScriptArgument structure{"structure", "a structure of the dataset shown, by id or name"};
  const ScriptArgument x{"x?", "window pixel (with y; or view_at)"}, y{"y?", "window pixel"};
  const ScriptArgument viewAt{"view_at?", "[fx, fy]: fractions of the view's rectangle, [0.5, 0.5] its centre"};
  return {"view",
          "the 3-D view and the explore panel",
          {
              {"select", {structure}, "Selects the structure as its list entry does: one the view does not show whole (or shows small) is framed from the side the view looks from (a click on it in the view keeps the camera).", &S::select},
              {"t", {{"value", "the blend t between bare and weighted rendering, 0..1"}}, "Sets the explore panel's t.", &S::setT},
              {"mode", {{"value", "\"wdt\" or \"bare\""}}, "Switches between weighted-distance and bare rendering.", &S::mode},
              {"view", {{"value", "anterior, posterior, lateral_left, lateral_right, superior or inferior"}}, "Turns the camera to a named view.", &S::view},
              {"hover", {x, y, viewAt}, "Moves the pointer there: the structure under it is highlighted.", &S::hover},
              {"click", {x, y, viewAt},
               "Clicks there: selects, or answers a locate question (waits until the answer's distance field is there).",
               &S::click},
              {"hover_structure", {structure},
               "Hovers the structure's projected centre; reports hover_structure {visible, x, y}.", &S::hoverStructure},
              {"click_structure", {structure},
               "Clicks the structure's projected centre (a locate answer on it); reports click_structure {visible}.",
               &S::clickStructure},
              {"orbit", {{"azimuth?", "degrees (default 0)"}, {"elevation?", "degrees (default 0)"}},
               "Orbits the camera as a drag does.", &S::orbit},
              {"zoom", {{"factor", "> 1 closer, < 1 farther"}}, "Zooms as the mouse wheel does.", &S::zoom},
              {"clip",
               {{"on?", "true (default) or false"}, {"axis?", "0, 1 or 2 (default 0)"}, {"flip?", "keep the other side (default false)"},
                {"offset?", "mm from the centre (default 0)"}},
               "Sets the clip plane of the explore panel.", &S::clip},
              {"cancel_field", {{"timeout_ms?", "how long to wait for a full-resolution field (default 60000)"}},
               "Waits for a full-resolution distance field to be computing, then cancels it as its button does.", &S::cancelField},
          }};
}

ScriptInterpreter::Outcome ScriptInterpreter::select(Context& c) {
  auto s = structureArg(c.model, c.action);
  if (!s) return tl::unexpected(s.error());
  c.model.clearHover();
  c.model.select((*s)->label);
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::setT(Context& c) {
  c.model.explore().setT(c.action.at("value").get<float>());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::mode(Context& c) {
  const std::string m = c.action.at("value");
  if (m != "wdt" && m != "bare") return fail("ui script: mode must be \"wdt\" or \"bare\", got \"" + m + "\"");
  c.model.explore().setBare(m == "bare");
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::view(Context& c) {
  const std::string name = c.action.at("value");
  if (!render::parseNamedView(name)) return fail("ui script: unknown view " + c.action.at("value").dump());
  if (auto st = c.model.setView(name); !st) return tl::unexpected(st.error());
  return Progress::Done;
}

namespace {
// A hover's or click's point in window pixels: "x", "y", or "view_at": [fx, fy], fractions of
// the view's rectangle (0.5, 0.5: its centre, wherever docked panels put it).
std::array<double, 2> pointOf(const json& action, const ViewLayout& layout) {
  if (!action.contains("view_at")) return {action.at("x").get<double>(), action.at("y").get<double>()};
  const auto f = action.at("view_at").get<std::array<double, 2>>();
  return {layout.viewLeft() + f[0] * layout.viewWidth(), f[1] * layout.viewHeight()};
}
}  // namespace

ScriptInterpreter::Outcome ScriptInterpreter::hover(Context& c) {
  const auto p = pointOf(c.action, c.model.layout());
  c.model.hoverAt(p[0], p[1]);
  return Progress::Done;
}

// A locate answer off its target is graded once its distance field is there: the click waits.
ScriptInterpreter::Outcome ScriptInterpreter::click(Context& c) {
  const auto p = pointOf(c.action, c.model.layout());
  if (c.first) c.model.clickAt(p[0], p[1]);
  return c.model.fields().clickPending() ? Progress::Running : Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::hoverStructure(Context& c) {
  auto s = structureArg(c.model, c.action);
  if (!s) return tl::unexpected(s.error());
  auto p = c.model.projectStructure((*s)->label);
  if (!p) {
    c.model.event({{"event", "hover_structure"}, {"structure", (*s)->id}, {"visible", false}});
  } else {
    c.model.event({{"event", "hover_structure"}, {"structure", (*s)->id}, {"visible", true}, {"x", (*p)[0]}, {"y", (*p)[1]}});
    c.model.hoverAt((*p)[0], (*p)[1]);
  }
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::clickStructure(Context& c) {
  if (c.first) {
    auto s = structureArg(c.model, c.action);
    if (!s) return tl::unexpected(s.error());
    auto p = c.model.projectStructure((*s)->label);
    c.model.event({{"event", "click_structure"}, {"structure", (*s)->id}, {"visible", p.has_value()}});
    if (p) c.model.clickAt((*p)[0], (*p)[1]);
  }
  return c.model.fields().clickPending() ? Progress::Running : Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::orbit(Context& c) {
  c.model.explore().orbit(c.action.value("azimuth", 0.0), c.action.value("elevation", 0.0));
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::zoom(Context& c) {
  c.model.explore().zoom(c.action.at("factor").get<double>());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::clip(Context& c) {
  ClipSettings clip;
  clip.on = c.action.value("on", true);
  clip.axis = c.action.value("axis", 0);
  clip.flip = c.action.value("flip", false);
  clip.offsetMm = c.action.value("offset", 0.0f);
  c.model.explore().setClip(clip);
  return Progress::Done;
}

// Waits for a full-resolution field to be computing, then cancels it as the button does.
ScriptInterpreter::Outcome ScriptInterpreter::cancelField(Context& c) {
  if (c.model.cancelFineField()) return Progress::Done;
  if (c.elapsedMs > c.action.value("timeout_ms", 60000.0)) return timedOut("cancel_field: no full-resolution field was computing");
  return Progress::Running;
}

}  // namespace at::app
