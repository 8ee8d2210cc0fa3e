// The desktop application: the frame loop and its wiring. The window (window.h), the volume view
// (volume_view.h) and the panels (panels.h) on one side; the model with its explore state, fields,
// scheduler and controllers (desktop_model.h) on the other; the UI script
// (script/script_interpreter.h) drives the model as the widgets do.
//
// A frame: input → model commands; the script's next actions; the model's frame (study view,
// controllers, fields handed to the view); the view renders what the scheduler plans; the panels
// draw; the window swaps (and saves a requested screenshot). With nothing left to do the loop
// waits for input.
#include <SDL.h>
#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <thread>

#include "cli_args.h"
#include "commands.h"
#include "ui/panels.h"
#include "script/script_interpreter.h"
#include "segment_editor/segment_controller.h"
#include "volume/png_image.h"
#include "ui/volume_view.h"
#include "ui/widget_rects.h"
#include "ui/window.h"

namespace at::app {

namespace {

using json = nlohmann::json;

struct AppOptions {
  DesktopOptions model;
  std::optional<std::string> script, screenshot, dbPath;
  int width = 1280, height = 720;
  double maxFps = 0;  // > 0: frames start at most this often (a display's rate for scripted runs)
};

class DesktopApp final : public ScriptHost {
 public:
  explicit DesktopApp(AppOptions options) : options_(std::move(options)), library_(defaultPresetsDir()) {}
  int run();

  // ScriptHost
  void requestScreenshot(const std::string& path) override { screenshotPath_ = path; }
  bool screenshotPending() const override { return screenshotPath_.has_value(); }
  std::string windowText() const override {
    const ViewLayout l = window_->layout();
    return std::to_string(l.windowW) + "x" + std::to_string(l.windowH);
  }
  std::string glText() const override { return window_->glDescription(); }
  bool drawsPanels() const override { return true; }
  nlohmann::json widgetRects() const override { return app::widgetRects(); }

 private:
  void handleEvent(const SDL_Event& e);
  // The window's layout with the explore panel as wide as it was last drawn.
  ViewLayout layout() const {
    ViewLayout l = window_->layout();
    l.panelPx = explore_.width();
    const bool editing = !model_->study().participantActive() && model_->segmenter().windowOpen &&
                         model_->segmenter().attached();
    dockPanels(l, editing, model_->slices().windowOpen && model_->slices().attached(),
               !model_->study().participantActive() && model_->expertOn());
    return l;
  }
  void frame();
  void drawUi();
  void takeScreenshot(render::RgbaImage& image, const Status& read);

  AppOptions options_;
  render::PresetLibrary library_;
  std::unique_ptr<LearningSession> session_;  // the process's one database connection
  std::unique_ptr<DesktopModel> model_;
  std::unique_ptr<DesktopWindow> window_;
  std::unique_ptr<VolumeView> view_;
  std::optional<ScriptInterpreter> script_;
  std::optional<std::string> screenshotPath_;
  std::string lastDrawError_;  // the UI drawing's GL error, reported once until a frame has none
  ExplorePanel explore_;
  StudyPanel study_;
  ImportPanel import_;
  AnalyticsPanel analytics_;
  SegmentPanel segment_;
  SlicesPanel slices_;
  ExpertPanel expert_;
  CourseEditorPanel courses_;
  bool quit_ = false;
  // Mouse
  bool leftDown_ = false, panDown_ = false, dragged_ = false;
  bool brushing_ = false;  // a segment-editor paint stroke on the view (left button down)
  double downX_ = 0, downY_ = 0, lastX_ = 0, lastY_ = 0;
};

int DesktopApp::run() {
  if (options_.script) {
    auto script = options_.script->empty() ? Result<ScriptInterpreter>(ScriptInterpreter({}, options_.screenshot))
                                           : ScriptInterpreter::load(*options_.script, options_.screenshot);
    if (!script) return reportError(script.error().message);
    script_.emplace(std::move(*script));
  }
  auto session = LearningSession::open(options_.dbPath);
  if (!session) return reportError(session.error().message);
  session_ = std::move(*session);
  model_ = std::make_unique<DesktopModel>(*session_, library_, options_.model, [this](json j) {
    if (!script_) return;
    std::printf("%s\n", j.dump().c_str());
    std::fflush(stdout);
  });
  if (auto st = model_->open(); !st) return reportError(st.error().message);
  auto window = DesktopWindow::open(options_.width, options_.height, script_.has_value());
  if (!window) return reportError(window.error().message);
  window_ = std::move(*window);
  view_ = std::make_unique<VolumeView>([this](const std::string& m) { model_->message(m); });
  // Known before the script's first step: a view that has not rendered yet is not settled.
  model_->setViewAvailable(view_->available());
  model_->event({{"event", "context"}, {"gl", window_->glDescription()}, {"note", window_->glNote()}, {"ui_scale", window_->uiScale()}});
  model_->setLayout(layout());
  model_->reframe();  // the start view framed for the window's size
  view_->prepare(*model_);
  while (!quit_) frame();
  return script_ ? script_->exitStatus() : 0;
}

void DesktopApp::frame() {
  const Clock::time_point start = Clock::now();
  SDL_Event e;
  if (model_->idle() && window_->waitEvent(e, 100)) handleEvent(e);
  while (window_->pollEvent(e)) handleEvent(e);
  if (quit_) return;
  model_->setLayout(layout());
  if (script_) {
    script_->step(*model_, *this, Clock::now());
    if (script_->finished()) {
      quit_ = true;
      return;
    }
  }
  FramePhases phases;
  const Clock::time_point modelStart = Clock::now();
  phases.inputMs = msBetween(start, modelStart);
  model_->beginFrame(view_->available() ? view_.get() : nullptr);
  const Clock::time_point viewStart = Clock::now();
  phases.modelMs = msBetween(modelStart, viewStart);
  view_->frame(*model_, viewStart);
  const Clock::time_point uiStart = Clock::now();
  phases.viewMs = msBetween(viewStart, uiStart);
  window_->beginFrame();
  drawUi();
  render::RgbaImage shot;
  const Status read = window_->endFrame(screenshotPath_ ? &shot : nullptr);
  if (std::string drawError = window_->takeDrawError(); drawError != lastDrawError_) {
    if (!drawError.empty())
      model_->message("drawing the window raised the GL error " + drawError +
                      ". If this keeps coming back, run with AT_GL_DEBUG=1 to see which GL call fails.");
    lastDrawError_ = std::move(drawError);
  }
  if (screenshotPath_) takeScreenshot(shot, read);
  const Clock::time_point end = Clock::now();
  phases.uiMs = msBetween(uiStart, end);
  model_->recorder().notePhases(phases);
  model_->endFrame(end, msBetween(start, end));
  if (options_.maxFps > 0)
    std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / options_.maxFps)));
}

void DesktopApp::takeScreenshot(render::RgbaImage& image, const Status& read) {
  const std::string path = *std::exchange(screenshotPath_, std::nullopt);
  const Status st = read ? writePng(path, render::toRgb(image)) : read;
  const ViewLayout l = window_->layout();
  if (!st) script_->screenshotFailed(st.error().message, *model_);
  else model_->event({{"event", "screenshot"}, {"path", path}, {"width", l.framebufferW}, {"height", l.framebufferH}});
}

void DesktopApp::drawUi() {
  clearWidgetRects();  // what the last frame drew becomes widgetRects()
  const ViewLayout& l = model_->layout();
  const float panelW = l.panelWidth();
  StudyController& study = model_->study();
  if (study.participantActive()) study_.drawParticipant(study, panelW, float(l.windowH));  // no names shown
  else explore_.draw(*model_, {window_->glDescription()});
  study_.drawCoordinator(study, panelW + 20, 20);
  if (!study.participantActive()) import_.draw(model_->imports(), panelW + 40, 40);
  if (!study.participantActive()) {  // over the view as the explore panel was drawn this frame, with a margin
    const float left = std::max(panelW, explore_.width());
    analytics_.draw(model_->analytics(), left + 16, 16, std::max(420.0f, float(l.windowW) - left - 32), float(l.windowH) - 32);
  }
  // The segment editor and the slice panes: docked beside and under the view when the layout
  // has room for them (dockPanels), else floating windows over it.
  const float viewW = l.viewWidth(), viewH = l.viewHeight();
  if (!study.participantActive()) {
    if (l.rightPx > 0) segment_.draw(model_->segmenter(), PanelRect{panelW + viewW, 0, l.rightPx, float(l.windowH)});
    else segment_.draw(model_->segmenter(), PanelRect{panelW + 60, 60, 0, 0});
    if (l.bottomPx > 0) slices_.draw(*model_, PanelRect{panelW, viewH, viewW, l.bottomPx});
    else slices_.draw(*model_, PanelRect{panelW + 80, float(l.windowH) * 0.45f, 0, 0});
  }
  if (!study.participantActive()) courses_.draw(*model_, panelW + 60, 60);
  // The renderer's texture as it is (GL's rows bottom first: uv0 is the image's left/bottom).
  if (const render::gl::DisplayImage& image = view_->image(); image.handle)
    ImGui::GetBackgroundDrawList()->AddImage(reinterpret_cast<ImTextureID>(image.handle), ImVec2(panelW, 0),
                                             ImVec2(panelW + viewW, viewH), ImVec2(image.uv0[0], image.uv1[1]),
                                             ImVec2(image.uv1[0], image.uv0[1]));
  const bool sliceShown = model_->examSlice() && (model_->exams().running() || !model_->examSlice()->highlighted.empty());
  // ... drawn over the 3-D view below
  if (view_->available() && view_->image().handle && !sliceShown)
    drawViewOverlay(model_->explore().camera(), panelW, 0, viewW, viewH, l.uiScale);
  if (!study.participantActive())  // a locate-on-slice exam item: the slice in place of the 3-D view
    explore_.exams().drawSlice(*model_, panelW, 0, viewW, viewH);
  if (!study.participantActive() && model_->expertOn() &&
      expert_.draw(model_->expert(), float(l.windowW) - kExpertPanelPx * l.uiScale, kExpertPanelPx * l.uiScale, float(l.windowH)))
    model_->expertEdited();
  if (!view_->available())
    ImGui::GetBackgroundDrawList()->AddText(ImVec2(panelW + 20, 20), IM_COL32(255, 140, 120, 255),
                                            "The volume view is unavailable (see the messages on the left).");
}

void DesktopApp::handleEvent(const SDL_Event& e) {
  DesktopWindow::forwardToImGui(e);
  if (e.type == SDL_QUIT) quit_ = true;
  if (e.type == SDL_WINDOWEVENT && e.window.event == SDL_WINDOWEVENT_CLOSE) quit_ = true;
  if (script_) return;  // scripted runs take no user input
  StudyController& study = model_->study();
  if (e.type == SDL_KEYDOWN && study.participantActive() && !DesktopWindow::imguiWantsText() &&
      (e.key.keysym.sym == SDLK_a || e.key.keysym.sym == SDLK_b))
    study.showSide(e.key.keysym.sym == SDLK_a ? 'A' : 'B');
  const bool overUi = DesktopWindow::imguiWantsMouse();
  const ViewLayout& layout = model_->layout();
  switch (e.type) {
    case SDL_MOUSEBUTTONDOWN:
      if (overUi || !layout.inView(e.button.x, e.button.y)) break;
      downX_ = lastX_ = e.button.x;
      downY_ = lastY_ = e.button.y;
      dragged_ = false;
      if (e.button.button == SDL_BUTTON_LEFT) leftDown_ = true;
      if (e.button.button == SDL_BUTTON_LEFT && model_->segmenter().brushesInView()) {  // a paint stroke, not an orbit
        brushing_ = true;
        model_->segmenter().beginStroke();
        model_->brushAt(e.button.x, e.button.y);
      }
      if (e.button.button == SDL_BUTTON_RIGHT || e.button.button == SDL_BUTTON_MIDDLE) panDown_ = true;
      break;
    case SDL_MOUSEBUTTONUP:
      if (e.button.button == SDL_BUTTON_LEFT && brushing_) {
        model_->segmenter().endStroke();
        brushing_ = leftDown_ = false;
        break;
      }
      if (e.button.button == SDL_BUTTON_LEFT && leftDown_ && !dragged_) model_->clickAt(e.button.x, e.button.y);
      if (e.button.button == SDL_BUTTON_LEFT) leftDown_ = false;
      if (e.button.button != SDL_BUTTON_LEFT) panDown_ = false;
      break;
    case SDL_MOUSEMOTION: {
      const double dx = e.motion.x - lastX_, dy = e.motion.y - lastY_;
      if (brushing_) {
        model_->brushAt(e.motion.x, e.motion.y);
      } else if (leftDown_ || panDown_) {
        if (std::abs(e.motion.x - downX_) + std::abs(e.motion.y - downY_) > 3) dragged_ = true;
        if (leftDown_ && dragged_) model_->explore().orbit(-dx * 0.4, dy * 0.4);
        if (panDown_) model_->explore().pan(dx, dy, int(layout.viewHeight()));
        if (!(leftDown_ && dragged_) && !panDown_) model_->explore().noteActivity();
        lastX_ = e.motion.x;
        lastY_ = e.motion.y;
      } else if (!overUi) {
        model_->hoverAt(e.motion.x, e.motion.y);
      }
      break;
    }
    case SDL_MOUSEWHEEL:
      if (!overUi && e.wheel.y != 0) model_->explore().zoom(std::pow(1.1, double(e.wheel.y)));
      break;
    default:
      break;
  }
}

constexpr const char* kDesktopHelp =
    "usage: anatomy-tutor [desktop] [--course ID] [--dataset D] [--ui-script FILE.json [--screenshot OUT.png]] [--size WxH]\n"
    "                             [--render-scale S] [--frame-budget MS] [--max-fps N] [--no-prefetch] [--db PATH]\n"
    "                             [--user NAME]\n"
    "       anatomy-tutor desktop --help-actions [--markdown] | --help ACTION\n"
    "  Opens the desktop app on a course (explore: hover to highlight, click to select).\n"
    "  --course     the course to start on, by id (`anatomy-tutor courses`; e.g. skull, the head CT's\n"
    "               course): its dataset, on its first lesson's first view (default: temporal_bone)\n"
    "  --dataset    phantom, phantom:N, skull, a dataset imported into --db, or a volume file or DICOM\n"
    "               folder (default: the course's dataset)\n"
    "  --ui-script  replay {\"actions\": [...]}: `desktop --help-actions` lists every action with its\n"
    "               arguments, by feature; `desktop --help ACTION` describes one\n"
    "  --db         the database: imported datasets, presets saved in the expert panel, studies,\n"
    "               lesson progress (default: the user's)\n"
    "  --user       whose lesson progress to show and record (default: student; the same name as\n"
    "               `anatomy-tutor play --user` shares the progress; created when new)\n"
    "  --screenshot save the window as PNG once the script has run and the view has settled\n"
    "  --size       window size in logical pixels (default 1280x720)\n"
    "  --render-scale  largest resolution of the full-quality volume image, 0.1..1 (default 1); at rest\n"
    "               the full quality (shading included) is refined over frames, at a lower resolution\n"
    "               where the GL is too slow to reach it within about 2 s (the panel says which)\n"
    "  --frame-budget  frame time the refinement at rest stays within (default 100 ms)\n"
    "  --max-fps    start frames at most N times a second (scripted runs swap without vsync and\n"
    "               otherwise draw as fast as they can; 60 measures them as on a 60 Hz display)\n"
    "  --no-prefetch  do not compute a lesson's next steps' distance fields while the student reads\n"
    "               (to measure what the prefetch saves)\n"
    "  --db, --user and --size may also stand before the command.\n"
    "  AT_GL_DEBUG=1 (environment): a debug GL context; each GL error is printed with the call that\n"
    "               raised it (for a bug report when the view says it met a GL error)\n";

}  // namespace

int runDesktop(const std::vector<std::string>& argv) {
  auto args = cli::Args::parse(argv, {"dataset", "course", "ui-script", "screenshot", "render-scale", "frame-budget", "max-fps"},
                               {"no-prefetch", "help-actions", "markdown"});
  if (!args) return reportError("desktop: " + args.error().message, 2);
  if (args->has("help-actions")) {
    std::fputs((args->has("markdown") ? ScriptInterpreter::actionsMarkdown() : ScriptInterpreter::actionsText()).c_str(), stdout);
    return 0;
  }
  if (args->has("help")) {
    if (args->positional().empty()) {
      std::fputs(kDesktopHelp, stdout);
      return 0;
    }
    const auto entry = ScriptInterpreter::actionText(args->positional()[0]);
    if (!entry) return reportError("desktop: no UI-script action '" + args->positional()[0] + "' (see --help-actions)", 2);
    std::fputs(entry->c_str(), stdout);
    return 0;
  }
  if (!args->positional().empty()) return reportError("desktop: unexpected argument '" + args->positional()[0] + "' (see --help)", 2);
  AppOptions options;
  options.model.dataset = args->valueOr("dataset", "");
  options.model.course = args->valueOr("course", "");
  options.script = args->value("ui-script");
  options.screenshot = args->value("screenshot");
  options.dbPath = args->db();
  if (auto user = args->user()) options.model.userName = *user;
  if (auto size = args->size()) {
    if (size->width < 400 || size->height < 300) return reportError("desktop: --size must be WxH, at least 400x300", 2);
    options.width = size->width;
    options.height = size->height;
  }
  auto frameBudget = args->number("frame-budget", options.model.frameBudgetMs);
  if (!frameBudget || !(*frameBudget >= 10 && *frameBudget <= 100000))
    return reportError("desktop: --frame-budget must be a number of milliseconds in 10..100000", 2);
  options.model.frameBudgetMs = *frameBudget;
  auto maxFps = args->number("max-fps", 0);
  if (!maxFps || !(*maxFps == 0 || (*maxFps >= 1 && *maxFps <= 1000))) return reportError("desktop: --max-fps must be a number in 1..1000", 2);
  options.maxFps = *maxFps;
  options.model.prefetchLessonFields = !args->has("no-prefetch");
  auto renderScale = args->number("render-scale", options.model.renderScale);
  if (!renderScale || !(*renderScale >= 0.1 && *renderScale <= 1)) return reportError("desktop: --render-scale must be a number in 0.1..1", 2);
  options.model.renderScale = *renderScale;
  if (options.screenshot && !options.script) options.script = std::string();  // the default view
  options.model.scripted = options.script.has_value();
  if (!displayAvailable()) return reportError("desktop: no display (none named in DISPLAY/WAYLAND_DISPLAY, or it cannot be opened)");
  return DesktopApp(std::move(options)).run();
}

}  // namespace at::app
