// [SECTIONS] the loop · the view · waiting and output
#include "script_interpreter.h"

#include <algorithm>
#include <fstream>

#include "core/atomic_file.h"
#include "render/camera.h"

namespace at::app {

using json = nlohmann::json;

namespace {
// A timeout: something the script waited for never came (exit status 1, not 2).
tl::unexpected<Error> timedOut(const std::string& what) { return fail(ErrorKind::Unavailable, "ui script: " + what); }

// The structure named by the action's "structure" (its id or name) in the dataset on screen.
Result<const Structure*> structureArg(const DesktopModel& model, const json& a) {
  const std::string id = a.value("structure", "");
  const Structure* s = model.dataset().findStructure(id);
  if (!s) return fail("ui script: no structure '" + id + "' in dataset '" + model.dataset().id + "'");
  return s;
}
}  // namespace

const std::map<std::string, ScriptInterpreter::Handler>& ScriptInterpreter::handlers() {
  using S = ScriptInterpreter;
  static const std::map<std::string, Handler> table = {
      {"select", &S::select},           {"t", &S::setT},
      {"mode", &S::mode},               {"view", &S::view},
      {"hover", &S::hover},             {"click", &S::click},
      {"hover_structure", &S::hoverStructure}, {"click_structure", &S::clickStructure},
      {"orbit", &S::orbit},             {"zoom", &S::zoom},
      {"clip", &S::clip},               {"expert", &S::expert},
      {"cancel_field", &S::cancelField}, {"wait", &S::wait},
      {"wait_field", &S::waitField},    {"screenshot", &S::screenshot},
      {"widgets", &S::widgets},
      {"layout", &S::layout},
      {"record", &S::record},           {"report", &S::report},
      {"hover_sweep", &S::hoverSweep},  {"lesson_user", &S::lessonUser},
      {"lessons", &S::lessonList},      {"lesson", &S::lesson},
      {"lesson_next", &S::lessonNext},  {"answer", &S::answer},
      {"lesson_back", &S::lessonReview}, {"show_me", &S::lessonReview},
      {"lesson_review_item", &S::lessonReview},
      {"review", &S::review},           {"lesson_close", &S::lessonClose},
      {"exams", &S::examList},          {"exam", &S::exam},
      {"exam_item", &S::examItem},      {"exam_answer", &S::examAnswer},
      {"slice_click", &S::sliceClick},  {"slice_click_structure", &S::sliceClickStructure},
      {"exam_finish", &S::examFinish},  {"exam_leave", &S::examLeave},
      {"exam_review_item", &S::examReviewItem},
      {"analytics", &S::analytics},
      {"tf_add_point", &S::tfEdit},     {"tf_move_point", &S::tfEdit},
      {"tf_delete_point", &S::tfEdit},  {"tf_colour", &S::tfEdit},
      {"preset_set", &S::presetSet},    {"preset_save", &S::presetSave},
      {"study_start", &S::studyStart},  {"study_toggle", &S::study},
      {"study_rate", &S::study},        {"study_comment", &S::study},
      {"study_next", &S::study},        {"study_close", &S::study},
      {"coordinator_open", &S::coordinatorOpen}, {"coordinator_export", &S::coordinatorExport},
      {"coordinator_summary", &S::coordinatorSummary}, {"import", &S::importDataset},
      {"cancel_import", &S::cancelImport}, {"open_imported", &S::openImported},
      {"segment_open", &S::segmentOpen}, {"segment_label", &S::segmentLabel},
      {"segment_slice", &S::segmentSlice}, {"segment_seed", &S::segmentSeed},
      {"segment_grow", &S::segmentGrow}, {"segment_undo", &S::segmentUndo},
      {"segment_redo", &S::segmentRedo}, {"segment_review", &S::segmentReview},
      {"segment_tool", &S::segmentTool},
      {"segment_clear_seeds", &S::segmentClearSeeds}, {"segment_save", &S::segmentSave},
      {"segment_threshold", &S::segmentThreshold}, {"segment_margin", &S::segmentMargin},
      {"segment_hollow", &S::segmentHollow}, {"slices_open", &S::slicesOpen},
      {"course_new", &S::courseNew},    {"course_open", &S::courseOpen},
      {"course_lesson", &S::courseLesson}, {"course_show", &S::courseShow},
      {"course_question", &S::courseQuestion}, {"course_step", &S::courseStep},
      {"course_save", &S::courseSave},  {"course_export", &S::courseSave},
      {"course_open_package", &S::courseSave}, {"open_dataset", &S::openDataset},
  };
  return table;
}

std::vector<std::string> ScriptInterpreter::actionNames() {
  std::vector<std::string> names;
  for (const auto& [name, handler] : handlers()) names.push_back(name);
  return names;
}

// ---------------------------------------------------------------------------------------------
// The loop

Result<ScriptInterpreter> ScriptInterpreter::load(const std::string& path, std::optional<std::string> finalScreenshot) {
  if (auto ok = checkRegularFile(path, path); !ok) return tl::unexpected(ok.error());
  std::ifstream in(path);
  if (!in) return fail(ErrorKind::NotFound, path + ": cannot open the UI script");
  json script;
  try {
    in >> script;
  } catch (const json::exception& e) {
    return fail(path + ": not JSON (" + e.what() + ")");
  }
  if (!script.is_object() || !script.contains("actions") || !script["actions"].is_array())
    return fail(path + ": a UI script is an object with an \"actions\" list");
  return ScriptInterpreter(script["actions"].get<std::vector<json>>(), std::move(finalScreenshot));
}

ScriptInterpreter::ScriptInterpreter(std::vector<json> actions, std::optional<std::string> finalScreenshot)
    : actions_(actions.begin(), actions.end()), finalScreenshot_(std::move(finalScreenshot)) {}

void ScriptInterpreter::finish(int status) {
  status_ = status;
  finished_ = true;
}

void ScriptInterpreter::screenshotFailed(const std::string& why, DesktopModel& model) {
  model.message(why);
  finish(1);
}

void ScriptInterpreter::step(DesktopModel& model, ScriptHost& host, Clock::time_point now) {
  if (finished_ || host.screenshotPending()) return;
  while (!actions_.empty()) {
    const json a = actions_.front();  // a copy: an action may add actions (hover_sweep)
    if (!a.is_object() || !a.contains("do") || !a["do"].is_string()) {
      model.message("ui script: every action must be an object with a \"do\" string, got " + a.dump());
      return finish(2);
    }
    const std::string what = a["do"];
    const auto handler = handlers().find(what);
    if (handler == handlers().end()) {
      model.message("ui script: unknown action \"" + what + "\"");
      return finish(2);
    }
    const bool first = !begun_;
    if (first) {
      begun_ = true;
      actionStart_ = now;
    }
    Context context{model, host, a, first, msBetween(actionStart_, now), actionStart_};
    Outcome outcome = Progress::Done;
    try {
      outcome = (this->*handler->second)(context);
    } catch (const std::exception& e) {  // nlohmann's type and range errors: a malformed action
      outcome = fail("ui script: action " + a.dump() + ": " + e.what());
    }
    if (!outcome) {
      model.message(outcome.error().message);
      return finish(outcome.error().kind == ErrorKind::Unavailable ? 1 : 2);
    }
    if (*outcome == Progress::Running) return;
    if (!actions_.empty() && actions_.front() == a) actions_.pop_front();  // hover_sweep replaced itself
    begun_ = false;
    if (host.screenshotPending()) return;  // the frame draws it first
  }
  // All actions done: the final screenshot once the view has settled.
  if (finalScreenshot_) {
    if (!begun_) {
      begun_ = true;
      actionStart_ = now;
    }
    if (!model.settled() && msBetween(actionStart_, now) < 120000) return;
    host.requestScreenshot(*std::exchange(finalScreenshot_, std::nullopt));
    return;
  }
  finish(status_);
}

// ---------------------------------------------------------------------------------------------
// The view

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

// {"do": "layout"}: an event with the window's size and the view's rectangle (window pixels), and
// whether the segment editor and the slice panes are docked beside it.
ScriptInterpreter::Outcome ScriptInterpreter::layout(Context& c) {
  const ViewLayout& l = c.model.layout();
  c.model.event({{"event", "layout"},
                 {"window", {l.windowW, l.windowH}},
                 {"view", {{"x", l.viewLeft()}, {"y", 0}, {"width", l.viewWidth()}, {"height", l.viewHeight()}}},
                 {"editor_docked", l.rightPx > 0},
                 {"slices_docked", l.bottomPx > 0}});
  return Progress::Done;
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

ScriptInterpreter::Outcome ScriptInterpreter::expert(Context& c) {
  c.model.setExpert(c.action.value("on", true));
  return Progress::Done;
}

// Waits for a full-resolution field to be computing, then cancels it as the button does.
ScriptInterpreter::Outcome ScriptInterpreter::cancelField(Context& c) {
  if (c.model.cancelFineField()) return Progress::Done;
  if (c.elapsedMs > c.action.value("timeout_ms", 60000.0)) return timedOut("cancel_field: no full-resolution field was computing");
  return Progress::Running;
}

// ---------------------------------------------------------------------------------------------
// Waiting and output

ScriptInterpreter::Outcome ScriptInterpreter::wait(Context& c) {
  return c.elapsedMs < c.action.value("ms", 0.0) ? Progress::Running : Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::waitField(Context& c) {
  if (c.model.settled()) {
    // How long the view took to be final: its field on screen and the full-quality image of it
    // rendered ("ms"); "field_ms": when the field alone was on screen (0: it already was).
    const Clock::time_point shown = c.model.fields().shownAt();
    const double fieldMs = shown > c.startedAt ? msBetween(c.startedAt, shown) : 0.0;
    c.model.event({{"event", "field_settled"}, {"ms", c.elapsedMs}, {"field_ms", fieldMs}});
    return Progress::Done;
  }
  if (c.elapsedMs > c.action.value("timeout_ms", 120000.0)) return timedOut("wait_field timed out");
  return Progress::Running;
}

ScriptInterpreter::Outcome ScriptInterpreter::screenshot(Context& c) {
  c.host.requestScreenshot(c.action.at("path").get<std::string>());
  return Progress::Done;
}

// {"do": "widgets"}: where frames drawn wholly after the action began drew the named widgets, once
// two frames in a row agree (ImGui applies a scroll the frame after it is asked for), with the
// window's size ("1280x720") [widgets]; at most 2 s.
ScriptInterpreter::Outcome ScriptInterpreter::widgets(Context& c) {
  const json drawn = c.host.widgetRects();
  const std::uint64_t frame = drawn.value("frame", std::uint64_t(0));
  if (c.first) {
    widgetsAfterFrame_ = frame + 1;  // the frame being drawn may predate the action
    widgetsLast_ = json();
  }
  if (c.host.drawsPanels() && c.elapsedMs < 2000) {
    if (frame <= widgetsAfterFrame_) return Progress::Running;
    if (drawn.at("widgets") != widgetsLast_) {
      widgetsLast_ = drawn.at("widgets");
      return Progress::Running;
    }
  }
  c.model.event({{"event", "widgets"}, {"window", c.host.windowText()}, {"widgets", drawn.at("widgets")}});
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::record(Context& c) {
  if (c.action.value("on", true)) c.model.recorder().start();
  else c.model.recorder().stop();
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::report(Context& c) {
  FrameRecorder::Context context;
  context.frameBudgetMs = c.model.options().frameBudgetMs;
  context.fieldsCancelled = c.model.fields().cancelledCount();
  context.window = c.host.windowText();
  context.gl = c.host.glText();
  const json r = c.model.recorder().report(context);
  c.model.event(r);
  const std::string out = c.action.value("out", "");
  c.model.recorder().stop();
  if (!out.empty())
    if (auto ok = writeFileAtomically(out, r.dump(2) + "\n"); !ok) return fail(ErrorKind::Io, "ui script: report: " + ok.error().message);
  return Progress::Done;
}

// Hovers each visible structure's projected centroid in turn and rests `dwell_ms` on it, recording.
ScriptInterpreter::Outcome ScriptInterpreter::hoverSweep(Context& c) {
  const double dwell = c.action.value("dwell_ms", 1200.0);
  std::vector<json> sweep;
  sweep.push_back({{"do", "record"}, {"on", true}});
  for (const auto& [system, list] : c.model.explore().bySystem())
    for (const Structure* s : list) {
      sweep.push_back({{"do", "hover_structure"}, {"structure", s->id}});
      sweep.push_back({{"do", "wait"}, {"ms", dwell}});
    }
  sweep.push_back({{"do", "report"}, {"out", c.action.value("out", "")}});
  actions_.pop_front();
  actions_.insert(actions_.begin(), sweep.begin(), sweep.end());
  return Progress::Done;
}

}  // namespace at::app
