// The UI script's waiting and output actions: waits, screenshots, the frame recorder's report and
// what the window drew (its widgets, the view's rectangle).
#include "script/script_answers.h"
#include "script/script_interpreter.h"

#include "core/atomic_file.h"

namespace at::app {

using json = nlohmann::json;

ScriptInterpreter::Feature ScriptInterpreter::outputActions() {
  using S = ScriptInterpreter;
  return {"output",
          "waiting, screenshots and measurements",
          {
              {"wait", {{"ms?", "milliseconds (default 0)"}}, "Waits that long (frames go on).", &S::wait},
              {"wait_field", {{"timeout_ms?", "default 120000; a timeout ends the script with status 1"}},
               "Waits until the view is final (full quality, its distance field shown); reports field_settled {ms, field_ms: when the field alone was on screen}.",
               &S::waitField},
              {"screenshot", {{"path", "PNG file to write"}}, "Saves the window once the current frame is drawn.", &S::screenshot},
              {"widgets", {},
               "Reports widgets {window, widgets}: where the last settled frames drew the named widgets (at most 30 frames).",
               &S::widgets},
              {"layout", {},
               "Reports layout {window, view, editor_docked, expert_docked, slices_docked}: the view's rectangle in window pixels.",
               &S::layout},
              {"record", {{"on?", "true (default) starts, false stops"}}, "Starts or stops the frame recorder.", &S::record},
              {"report", {{"out?", "JSON file to write the report to"}},
               "Reports the frame recorder's measurements (frame times, highlights) and stops it.", &S::report},
              {"hover_sweep", {{"dwell_ms?", "rest on each structure (default 1200)"}, {"out?", "JSON file for the report"}},
               "Records while hovering every listed structure in turn, then reports.", &S::hoverSweep},
          }};
}

// {"do": "layout"}: an event with the window's size and the view's rectangle (window pixels), and
// whether the segment editor, the expert panel and the slice panes are docked beside it.
ScriptInterpreter::Outcome ScriptInterpreter::layout(Context& c) {
  const ViewLayout& l = c.model.layout();
  c.model.event({{"event", "layout"},
                 {"window", {l.windowW, l.windowH}},
                 {"view", {{"x", l.viewLeft()}, {"y", 0}, {"width", l.viewWidth()}, {"height", l.viewHeight()}}},
                 {"editor_docked", l.rightPx > 0},
                 {"expert_docked", l.expertPx > 0},
                 {"slices_docked", l.bottomPx > 0}});
  return Progress::Done;
}

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
// two frames in a row agree (ImGui applies a scroll the frame after it is asked for, and shows a
// scroll bar the frame after the content outgrows its panel), with the window's size ("1280x720")
// [widgets]; at most 30 frames (widgets that keep moving), counted in frames rather than seconds so
// that a slow or busy machine (software GL, other work) settles as a fast one does; 60 s at most.
ScriptInterpreter::Outcome ScriptInterpreter::widgets(Context& c) {
  constexpr std::uint64_t kMaxSettleFrames = 30;
  const json drawn = c.host.widgetRects();
  const std::uint64_t frame = drawn.value("frame", std::uint64_t(0));
  if (c.first) {
    widgetsAfterFrame_ = frame + 1;  // the frame being drawn may predate the action
    widgetsLast_ = json();
  }
  if (c.host.drawsPanels() && frame < widgetsAfterFrame_ + kMaxSettleFrames && c.elapsedMs < 60000) {
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
