// The desktop application (issue 7): an SDL2 window with an OpenGL context, Dear ImGui panels and
// the render/gl ray caster drawing the volume view. Explore level: structure browser, hover to
// highlight (fields computed off the UI thread by wdt::FieldService), click to select, the structure's
// WDT or bare preset with the blend t, named views, orbit/zoom/pan and a clipping plane.
//
// Adaptive quality: while the view or the hovered structure changes, the volume is rendered into a
// smaller target with longer steps (the level whose predicted cost fits the interaction budget);
// when the user rests, each frame renders one level finer, up to full resolution or to the finest
// level predicted to fit the frame budget (--frame-budget; "Full quality at rest" and scripted
// screenshots lift it); an unchanged view is not rendered again. The frame never waits for a distance field: until the hovered structure's
// field arrives the previous one stays on screen.
//
// Long work: the import window (ImportPanel) loads and registers datasets on a background thread
// with progress and Cancel, and an imported dataset can be opened in place (showDataset); a
// running full-resolution field shows its passes and can be cancelled (the coarse field stays).
//
// Scripted mode (--ui-script FILE.json [--screenshot OUT.png]) replays actions from
// {"actions": [{"do": "select", "structure": "cochlea"}, …]} and prints one JSON line per event.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <SDL.h>
#include <imgui.h>
#include <backends/imgui_impl_opengl3.h>
#include <backends/imgui_impl_sdl.h>
#include <nlohmann/json.hpp>

#include "core/strings.h"
#include "cli_args.h"
#include "commands.h"
#include "dataset_resolver.h"
#include "desktop_support.h"
#include "import_panel.h"
#include "learning_session.h"
#include "lesson_panel.h"
#include "lessons/curriculum.h"
#include "render/gl/volume_renderer.h"
#include "render/gl/window_target.h"
#include "render/scene.h"
#include "render/structure_pick.h"
#include "study_panel.h"
#include "tf_editor_panel.h"
#include "volume/dataset_source.h"
#include "volume/mask.h"
#include "volume/png_image.h"
#include "wdt/answer_keys.h"
#include "wdt/field_service.h"

namespace at::app {

namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

double msBetween(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Render quality levels: fraction of the view's pixels per axis and step length factor.
struct QualityLevel {
  double scale;
  double stepFactor;
};
constexpr QualityLevel kLevels[] = {{0.05, 4.0}, {0.1, 3.0}, {0.2, 2.0}, {0.35, 1.5}, {0.6, 1.0}, {1.0, 1.0}};
constexpr int kFullLevel = 5;
constexpr double kInteractionBudgetMs = 55;  // predicted render cost allowed while the user moves
constexpr double kRefineBudgetMs = 150;      // at rest, levels predicted this cheap are skipped over
constexpr double kRestAfterMs = 250;        // no change for this long = the user rests
constexpr double kFieldUploadStepMs = 20;  // per frame, for a field uploaded from host memory
constexpr double kRefineFieldAfterMs = 400;  // mouse resting this long on a structure → full-res field

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = p / 100.0 * double(v.size() - 1);
  const std::size_t lo = std::size_t(std::floor(pos)), hi = std::min(v.size() - 1, lo + 1);
  return v[lo] + (v[hi] - v[lo]) * (pos - double(lo));
}

using wdt::FieldRequest;
using wdt::FieldService;
using wdt::FinishedField;

// RAII for SDL, the window with its GL context, and the ImGui context with its backends.
struct SdlSession {
  bool ok = false;
  SdlSession() { ok = SDL_Init(SDL_INIT_VIDEO | SDL_INIT_TIMER | SDL_INIT_EVENTS) == 0; }
  ~SdlSession() {
    if (ok) SDL_Quit();
  }
};

struct Window {
  SDL_Window* window = nullptr;
  SDL_GLContext context = nullptr;
  ~Window() {
    if (context) SDL_GL_DeleteContext(context);
    if (window) SDL_DestroyWindow(window);
  }
};

// Tries OpenGL 4.5, then 4.3 core, then whatever the driver gives; `note` says which was taken.
Result<std::unique_ptr<Window>> openWindow(int width, int height, bool resizable, std::string& note) {
  auto w = std::make_unique<Window>();
  struct Attempt {
    int major, minor;
    bool core;
  };
  for (const Attempt a : {Attempt{4, 5, true}, Attempt{4, 3, true}, Attempt{0, 0, false}}) {
    SDL_GL_ResetAttributes();
    if (a.core) {
      SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
      SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, a.major);
      SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, a.minor);
    }
    SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
    SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 0);
    Uint32 flags = SDL_WINDOW_OPENGL | SDL_WINDOW_ALLOW_HIGHDPI | SDL_WINDOW_SHOWN;
    if (resizable) flags |= SDL_WINDOW_RESIZABLE;
    if (!w->window) {
      w->window = SDL_CreateWindow("Anatomy Tutor", SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, width, height, flags);
      if (!w->window) return fail(std::string("cannot open a window: ") + SDL_GetError());
    }
    w->context = SDL_GL_CreateContext(w->window);
    if (w->context) {
      note = a.core ? "asked for OpenGL " + std::to_string(a.major) + "." + std::to_string(a.minor) + " core"
                    : "no 4.x core context; took the driver's default";
      return w;
    }
    note += std::string(a.core ? "OpenGL " + std::to_string(a.major) + "." + std::to_string(a.minor) + " core refused (" : "(") +
            SDL_GetError() + "); ";
  }
  return fail("cannot create an OpenGL context: " + note);
}

struct ImGuiSession {
  bool sdl = false, gl = false;
  ImGuiSession() {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // layout is the app's, not a file beside the binary
  }
  ~ImGuiSession() {
    if (gl) ImGui_ImplOpenGL3_Shutdown();
    if (sdl) ImGui_ImplSDL2_Shutdown();
    ImGui::DestroyContext();
  }
};

struct FrameRecord {
  double ms = 0;
  int level = -1;          // quality level rendered this frame, -1 when the image was reused
  bool interacting = false;
  double uploadMs = 0;     // distance field uploaded to the GL this frame
  double renderMs = 0;     // the volume render of this frame (0 when reused)
};

class DesktopApp {
 public:
  struct Options {
    std::string dataset;            // empty: the default course's dataset; else as openNamedDataset takes it
    std::optional<std::string> script;
    std::optional<std::string> screenshot;
    std::optional<std::string> dbPath;  // the database: presets saved in the expert panel, studies, lessons, imports
    std::string userName = kDefaultLessonUser;  // whose lesson progress the lesson panel shows and records
    int width = 1280, height = 720;
    double renderScale = 1;         // resolution of the full-quality level (slow software GL: < 1)
    double frameBudgetMs = 100;     // at rest, finer levels predicted to cost more are not rendered
    double maxFps = 0;              // > 0: frames start at most this often (a display's refresh
                                    // rate for scripted runs, which swap without vsync)
  };

  explicit DesktopApp(Options options) : options_(std::move(options)), library_(defaultPresetsDir()) {}
  int run();

 private:
  // Set-up
  Status loadContent();
  // Shows `dataset` in the explore view (at start-up and when an imported one is opened), starting
  // on `startStructure` when it has one; an error leaves the current dataset on screen.
  Status showDataset(Dataset dataset, const std::string& startStructure, const std::string& startPreset);
  Status openGraphics();

  // Per frame
  void handleEvent(const SDL_Event& e);
  void updateFields();
  void renderVolume(Clock::time_point frameStart);
  void buildUi();
  void explorePanel(float panelW);
  void fieldProgress();  // the running field's progress; a full-resolution one can be cancelled
  float statusHeight() const;  // below the structure list: status lines and messages
  void cancelFineField();
  void syncStudyView();  // participant mode: the trial's structure with the preset of the side shown
  bool stepScript();  // true when the script has finished (or there is none)

  // Interaction
  void hoverAt(double x, double y);   // window coordinates (logical pixels)
  void clickAt(double x, double y);
  void setHovered(std::uint16_t label);
  void select(std::uint16_t label);
  void setView(const std::string& name);
  void showLessonStructure(const LessonPanel::Shown& shown);  // a lesson step's structure, preset and view
  lessons::RenderState renderState();                          // stored with each lesson answer
  bool inView(double x, double y) const;
  std::optional<std::array<double, 2>> projectStructure(std::uint16_t label) const;

  // State helpers
  std::uint16_t shownLabel() const { return hovered_ ? hovered_ : selected_; }
  const render::Preset& presetOf(std::uint16_t label, bool bare);
  render::Preset displayPreset();
  std::optional<FieldRequest> fieldRequest(std::uint16_t label, int downsample);
  int coarseDownsample() const;
  render::RenderSettings viewSettings(int level);
  std::string stateKey();
  bool settled();
  void markChanged() { lastChange_ = Clock::now(); }
  void message(const std::string& text);
  void event(json j);
  int finishScript(int status);
  void setExpert(bool on);  // opens the expert panel on the shown preset, or closes it
  void syncExpert();        // the edited preset changed: mode and t follow it
  bool expertOn() const { return expert_ && expert_->active(); }

  Options options_;
  std::unique_ptr<LearningSession> session_;  // the process's one database connection
  render::PresetLibrary library_;
  Dataset dataset_;
  render::GradientVolume gradients_;  // of dataset_'s volume
  std::vector<std::pair<std::string, std::vector<const Structure*>>> bySystem_;
  std::map<std::uint16_t, render::StructureFrame> frames_;
  std::map<std::pair<std::uint16_t, bool>, render::Preset> presets_;
  std::string startView_ = "lateral_right";

  // Graphics
  SdlSession sdl_;
  std::unique_ptr<Window> window_;
  std::unique_ptr<ImGuiSession> imgui_;
  std::optional<render::gl::VolumeRenderer> renderer_;
  std::optional<render::gl::ImageTexture> texture_;
  std::string glDescription_, glNote_;
  float uiScale_ = 1;
  int winW_ = 0, winH_ = 0, fbW_ = 0, fbH_ = 0;

  // Explore state
  std::uint16_t selected_ = 0, hovered_ = 0;
  bool bare_ = false;
  float t_ = 0.5f;
  render::Camera camera_;
  std::string viewName_;
  bool clipOn_ = false;
  int clipAxis_ = 0;  // 0: left–right (x), 1: anterior–posterior (y), 2: inferior–superior (z)
  bool clipFlip_ = false;
  float clipOffsetMm_ = 0;
  char search_[128] = "";

  // Fields
  std::unique_ptr<FieldService> worker_;
  std::shared_ptr<const DistanceField> field_;  // host copy of the field shown (picking); may lag a GPU field
  const void* fieldSource_ = nullptr;            // identity of the field in the texture; null = none
  std::uint16_t fieldLabel_ = 0;
  std::string fieldKey_;
  bool gpuFields_ = false;
  bool fieldUploading_ = false;  // a host field is going up slice by slice (see updateFields)
  std::string fieldStatus_;
  Clock::time_point hoverSince_ = Clock::now();
  std::string declinedFieldKey_;  // a full-resolution field the user cancelled: not asked again
  std::string lastFieldWarning_;  // shown once, not on every field
  bool cpuFieldNotice_ = false;   // told the user that fields run on the CPU

  // Rendering
  std::string renderedKey_;
  int renderedLevel_ = -1;
  double msPerUnit_ = 0;  // measured render cost per (pixel / step factor), EMA
  Clock::time_point lastChange_ = Clock::now();
  bool interacting_ = false;
  bool fullAtRest_ = false;  // render full quality at rest even beyond the frame budget
  bool restCapped_ = false;  // the image at rest stopped below full quality (frame budget)
  std::optional<std::pair<std::uint16_t, Clock::time_point>> pendingHighlight_;

  // Mouse
  bool leftDown_ = false, panDown_ = false, dragged_ = false;
  double downX_ = 0, downY_ = 0, lastX_ = 0, lastY_ = 0;
  std::optional<Vec3> lastPickMm_;  // where the last hover pick met the volume (LPS mm)
  // A locate answer waiting for the answer-key field of its target (asked of the field service,
  // never computed on this thread): graded with the click's weighted distance once it is there.
  struct PendingClick {
    std::string structure;  // clicked ("" for none)
    Vec3 pointMm{0, 0, 0};
    FieldRequest keyField;
  };
  std::optional<PendingClick> pendingClick_;
  bool servePendingClick();  // true while the click still waits for its field

  // Script and measurements
  std::deque<json> actions_;
  std::optional<Clock::time_point> waitUntil_;
  Clock::time_point actionStart_ = Clock::now();
  bool actionStarted_ = false;
  bool screenshotPending_ = false;
  std::string screenshotPath_;
  int scriptStatus_ = 0;
  bool quit_ = false;
  std::vector<FrameRecord> frameLog_;
  std::vector<double> latencies_;
  bool recording_ = false;
  std::vector<std::string> messages_;
  std::unique_ptr<StudyPanel> study_;
  std::unique_ptr<LessonPanel> lesson_;
  std::unique_ptr<TfEditorPanel> expert_;
  std::unique_ptr<ImportPanel> import_;
};

// ---------------------------------------------------------------------------------------------
// Set-up

Status DesktopApp::loadContent() {
  auto course = loadDefaultCourse();
  std::string datasetName = options_.dataset;
  std::string startStructure, startPreset;
  if (course) {
    if (datasetName.empty()) datasetName = course->datasetId;
    const auto views = firstLessonViews(*course);
    if (!views.empty()) {
      startStructure = views.front().structure;
      startPreset = views.front().presetId;
      startView_ = lessons::toString(views.front().view);
    }
  } else {
    message("default course: " + course.error().message);
  }
  if (datasetName.empty()) datasetName = "phantom";
  DatasetRequest request;
  request.name = datasetName;
  request.database = &session_->database();
  auto ds = openNamedDataset(request);
  if (!ds) return tl::unexpected(ds.error());
  return showDataset(std::move(*ds), startStructure, startPreset);
}

Status DesktopApp::showDataset(Dataset dataset, const std::string& startStructure, const std::string& startPreset) {
  if (dataset.structures.empty()) return fail("dataset '" + dataset.id + "' has no labelled structures");
  std::map<std::uint16_t, render::StructureFrame> frames;
  for (const Structure& s : dataset.structures)
    if (auto frame = render::structureFrame(dataset.labels, s.label)) frames[s.label] = *frame;
  if (frames.empty()) return fail("dataset '" + dataset.id + "': no structure has any voxel");
  if (expert_ && expertOn()) setExpert(false);
  worker_.reset();  // it holds a reference to dataset_
  dataset_ = std::move(dataset);
  gradients_ = render::computeGradientVolume(dataset_.volume);  // shading and picking share it
  frames_ = std::move(frames);
  bySystem_.clear();
  presets_.clear();
  for (const Structure& s : dataset_.structures) {
    if (!frames_.count(s.label)) continue;  // a named label with no voxels: not shown in the browser
    auto it = std::find_if(bySystem_.begin(), bySystem_.end(), [&](const auto& g) { return g.first == s.system; });
    if (it == bySystem_.end()) {
      bySystem_.push_back({s.system.empty() ? std::string("other") : s.system, {}});
      it = std::prev(bySystem_.end());
    }
    it->second.push_back(&s);
  }
  const Structure* start = startStructure.empty() ? nullptr : dataset_.findStructure(startStructure);
  if (!start || !frames_.count(start->label)) start = dataset_.findStructureByLabel(frames_.begin()->first);
  hovered_ = 0;
  selected_ = start->label;
  field_.reset();
  fieldSource_ = nullptr;
  fieldLabel_ = 0;
  fieldKey_.clear();
  declinedFieldKey_.clear();
  pendingHighlight_.reset();
  renderedKey_.clear();
  clipOffsetMm_ = 0;
  auto preset = presetForStep(library_, start->id, startPreset);
  if (preset) {
    bare_ = preset->mode == render::RenderMode::Bare;
    t_ = preset->t;
    presets_[{start->label, bare_}] = *preset;
  } else {
    message(preset.error().message);
  }
  pendingClick_.reset();
  worker_ = std::make_unique<FieldService>(dataset_.volume, dataset_.labels, 8);
  expert_ = std::make_unique<TfEditorPanel>(dataset_, session_->database(), [this](json j) { event(std::move(j)); });
  if (renderer_) {  // a dataset opened after start-up
    if (auto st = renderer_->setVolume(dataset_.volume, dataset_.labels, gradients_); !st) {
      message("volume renderer: " + st.error().message);
      renderer_.reset();
    }
    setView(viewName_.empty() ? startView_ : viewName_);
    if (lesson_) lesson_->setViewDataset(dataset_.id);
    event({{"event", "dataset"}, {"dataset", dataset_.id}, {"structures", dataset_.structures.size()},
           {"selected", start->id}});
  }
  return {};
}

Status DesktopApp::openGraphics() {
  if (!sdl_.ok) return fail(std::string("SDL cannot start its video subsystem: ") + SDL_GetError());
  auto window = openWindow(options_.width, options_.height, !options_.script, glNote_);
  if (!window) return tl::unexpected(window.error());
  window_ = std::move(*window);
  SDL_GL_MakeCurrent(window_->window, window_->context);
  SDL_GL_SetSwapInterval(options_.script ? 0 : 1);
  glDescription_ = render::gl::currentContextDescription();
  std::string ascii;  // ImGui's built-in font has no em dash
  for (std::size_t i = 0; i < glDescription_.size(); ++i) {
    if (glDescription_.compare(i, 3, "\u2014") == 0) {
      ascii += '-';
      i += 2;
    } else {
      ascii += glDescription_[i];
    }
  }
  glDescription_ = ascii;
  float ddpi = 96;
  if (SDL_GetDisplayDPI(0, &ddpi, nullptr, nullptr) != 0 || !(ddpi > 0)) ddpi = 96;
  uiScale_ = std::clamp(ddpi / 96.0f, 1.0f, 3.0f);

  imgui_ = std::make_unique<ImGuiSession>();
  ImGui::StyleColorsDark();
  ImGui::GetStyle().ScaleAllSizes(uiScale_);
  ImGui::GetIO().FontGlobalScale = uiScale_;
  imgui_->sdl = ImGui_ImplSDL2_InitForOpenGL(window_->window, window_->context);
  imgui_->gl = ImGui_ImplOpenGL3_Init("#version 150");
  if (!imgui_->sdl || !imgui_->gl) return fail("Dear ImGui could not start its SDL2/OpenGL3 backends");

  auto texture = render::gl::ImageTexture::create();
  if (!texture) return tl::unexpected(texture.error());
  texture_ = std::move(*texture);
  const auto version = render::gl::currentContextVersion();
  if (version[0] * 10 + version[1] < 43) {
    message("the volume view needs OpenGL 4.3; this context is " + glDescription_);
  } else {
    auto renderer = render::gl::VolumeRenderer::create();
    if (!renderer) {
      message("volume renderer: " + renderer.error().message);
    } else if (auto st = renderer->setVolume(dataset_.volume, dataset_.labels, gradients_); !st) {
      message("volume renderer: " + st.error().message);
    } else {
      renderer_ = std::move(*renderer);
    }
  }
  event({{"event", "context"}, {"gl", glDescription_}, {"note", glNote_}, {"ui_scale", uiScale_}});
  return {};
}

// ---------------------------------------------------------------------------------------------
// State helpers

void DesktopApp::message(const std::string& text) {
  messages_.push_back(text);
  if (messages_.size() > 6) messages_.erase(messages_.begin());
  std::fprintf(stderr, "anatomy-tutor: %s\n", text.c_str());
}

void DesktopApp::event(json j) {
  if (!options_.script) return;
  std::printf("%s\n", j.dump().c_str());
  std::fflush(stdout);
}

const render::Preset& DesktopApp::presetOf(std::uint16_t label, bool bare) {
  const auto key = std::make_pair(label, bare);
  auto it = presets_.find(key);
  if (it != presets_.end()) return it->second;
  render::Preset preset;
  const Structure* s = dataset_.findStructureByLabel(label);
  auto loaded = s ? library_.forStructure(s->id, bare ? render::RenderMode::Bare : render::RenderMode::Wdt)
                  : Result<render::Preset>(fail("no structure"));
  if (loaded) {
    preset = *loaded;
  } else {
    message("presets: " + loaded.error().message + " (using the built-in default)");
    preset.mode = bare ? render::RenderMode::Bare : render::RenderMode::Wdt;
  }
  return presets_.emplace(key, preset).first->second;
}

int DesktopApp::coarseDownsample() const {
  const Dims& d = dataset_.volume.dims();
  const int largest = std::max({d.x, d.y, d.z});
  return std::max(1, (largest + 63) / 64);  // about 64 voxels per axis: tens of ms on one core
}

std::optional<FieldRequest> DesktopApp::fieldRequest(std::uint16_t label, int downsample) {
  auto params = render::wdtParamsFor(expertOn() ? expert_->preset() : presetOf(label, false));
  if (!params) return std::nullopt;
  FieldRequest r;
  r.label = label;
  r.params = *params;
  r.params.downsample = downsample;
  r.params.backend = WdtBackend::Auto;
  return r;
}

render::Preset DesktopApp::displayPreset() {
  if (expertOn()) return expert_->preset();
  // Field modes show the structure whose field is uploaded; before any field, its bare preset.
  const bool useBare = bare_ || fieldLabel_ == 0;
  const std::uint16_t label = bare_ ? shownLabel() : (fieldLabel_ ? fieldLabel_ : shownLabel());
  render::Preset p = presetOf(label, useBare);
  p.t = t_;
  return p;
}

render::RenderSettings DesktopApp::viewSettings(int level) {
  render::RenderSettings s;
  s.preset = displayPreset();
  s.camera = camera_;
  const QualityLevel q = kLevels[std::clamp(level, 0, kFullLevel)];
  const int viewW = std::max(1, fbW_ - int(std::lround(320 * uiScale_ * double(fbW_) / std::max(1, winW_))));
  s.width = std::max(16, int(std::lround(viewW * q.scale * options_.renderScale)));
  s.height = std::max(16, int(std::lround(fbH_ * q.scale * options_.renderScale)));
  s.stepMm = render::effectiveStepMm(dataset_.volume.geometry, render::RenderSettings{}) * q.stepFactor;
  s.shading = level == kFullLevel;  // gradients cost six fetches per sample: only at rest
  s.jitter = level == kFullLevel;
  s.background = {0.04f, 0.04f, 0.05f, 1.0f};
  if (clipOn_) {
    Vec3 n{0, 0, 0};
    n[std::size_t(clipAxis_)] = clipFlip_ ? -1 : 1;
    s.clip = render::ClipPlane{n, dot(n, camera_.target) + double(clipOffsetMm_)};
  }
  return s;
}

std::string DesktopApp::stateKey() {
  const render::Preset p = displayPreset();
  const Vec3 eye = camera_.eye();
  char buf[512];
  std::snprintf(buf, sizeof buf, "%u|%d|%s|%.4f|%s|%.4f,%.4f,%.4f|%.4f,%.4f,%.4f|%.4f,%.4f,%.4f|%d%d%d%.3f|%dx%d",
                unsigned(bare_ ? shownLabel() : fieldLabel_), int(bare_), render::toString(p.mode), double(t_),
                fieldKey_.c_str(), eye[0], eye[1], eye[2], camera_.target[0], camera_.target[1], camera_.target[2],
                camera_.up()[0], camera_.up()[1], camera_.up()[2], int(clipOn_), clipAxis_, int(clipFlip_),
                double(clipOffsetMm_), fbW_, fbH_);
  return std::string(buf) + (expertOn() ? "|expert" + std::to_string(expert_->revision()) : "");
}

void DesktopApp::setView(const std::string& name) {
  const std::uint16_t label = shownLabel();
  auto it = frames_.find(label);
  if (it == frames_.end()) return;
  render::ViewRequest request;
  request.view = name;
  request.margin = 2.5;  // the explore view: the structure with room around it to orbit and hover
  request.width = std::max(1, fbW_);
  request.height = std::max(1, fbH_);
  auto settings = render::settingsFor(presetOf(label, bare_), it->second, request);
  if (!settings) {
    message(settings.error().message);
    return;
  }
  camera_ = settings->camera;
  viewName_ = name;
  markChanged();
}

bool DesktopApp::inView(double x, double y) const {
  return x >= 320 * uiScale_ && x < winW_ && y >= 0 && y < winH_;
}

std::optional<std::array<double, 2>> DesktopApp::projectStructure(std::uint16_t label) const {
  auto it = frames_.find(label);
  if (it == frames_.end()) return std::nullopt;
  const double left = 320 * uiScale_;
  const int viewW = int(winW_ - left), viewH = winH_;
  auto p = camera_.project(it->second.anchorMm, viewW, viewH);
  if (!p || (*p)[0] < 0 || (*p)[0] >= viewW || (*p)[1] < 0 || (*p)[1] >= viewH) return std::nullopt;
  return std::array<double, 2>{(*p)[0] + left, (*p)[1]};
}

void DesktopApp::showLessonStructure(const LessonPanel::Shown& shown) {
  const Structure* s = dataset_.findStructure(shown.structure);
  if (!s || !frames_.count(s->label)) {
    message("lesson step: no structure '" + shown.structure + "' in dataset '" + dataset_.id + "'");
    return;
  }
  auto preset = presetForStep(library_, s->id, shown.presetId);
  if (!preset) {
    message(preset.error().message);
    return;
  }
  bare_ = preset->mode == render::RenderMode::Bare;
  t_ = preset->t;
  presets_[{s->label, bare_}] = *preset;
  hovered_ = 0;
  select(s->label);
  setView(shown.view ? lessons::toString(*shown.view) : (viewName_.empty() ? startView_ : viewName_));
}

lessons::RenderState DesktopApp::renderState() {
  const render::Preset p = displayPreset();
  lessons::RenderState r;
  r.presetId = p.id.value_or(p.name);
  r.mode = bare_ ? "bare" : "wdt";
  r.t = t_;
  r.alpha = p.alpha;
  r.beta = p.lightingBeta;
  return r;
}

// ---------------------------------------------------------------------------------------------
// Interaction

void DesktopApp::setHovered(std::uint16_t label) {
  if (label == hovered_) return;
  hovered_ = label;
  declinedFieldKey_.clear();
  hoverSince_ = Clock::now();
  markChanged();
  const std::uint16_t shown = shownLabel();
  if (!bare_ && shown != fieldLabel_)
    pendingHighlight_ = std::make_pair(shown, Clock::now());
  else if (bare_)
    pendingHighlight_ = std::make_pair(shown, Clock::now());
  else
    pendingHighlight_.reset();
}

void DesktopApp::hoverAt(double x, double y) {
  if (study_->participantActive()) return;  // the view stays on the trial's structure
  if (!inView(x, y)) {
    setHovered(0);
    return;
  }
  const double left = 320 * uiScale_;
  render::RenderSettings s = viewSettings(kFullLevel);
  // Picking classifies like the WDT view (bare mode shows only one structure, yet the user points
  // at what lies under the cursor in the anatomy).
  s.preset = presetOf(fieldLabel_ ? fieldLabel_ : shownLabel(), false);
  render::SceneVolumes scene;
  scene.volume = &dataset_.volume;
  scene.labels = &dataset_.labels;
  scene.field = field_ ? &field_->distances : nullptr;
  scene.gradients = &gradients_;
  scene.selected = fieldLabel_;
  const render::TransferFunction2D table = render::shadingTable(s.preset);
  const double px = (x - left) / std::max(1.0, winW_ - left) * s.width, py = y / std::max(1, winH_) * s.height;
  const render::PickResult hit = render::pickStructure(scene, s, table, px, py);
  if (hit.hit) lastPickMm_ = hit.pointMm;
  else lastPickMm_.reset();
  const std::uint16_t label = hit.hit && frames_.count(hit.label) ? hit.label : 0;
  if (label != hovered_) {
    const Structure* st = dataset_.findStructureByLabel(label);
    json e = {{"event", "hover"}, {"x", x}, {"y", y}, {"label", label}, {"structure", st ? st->id : ""}};
    if (st) {  // the colour its WDT preset draws the structure itself in (render_settings.h)
      const auto& rgb = presetOf(label, false).highlightRgb;
      e["highlight_rgb"] = {rgb[0], rgb[1], rgb[2]};
    }
    event(e);
  }
  setHovered(label);
}

void DesktopApp::select(std::uint16_t label) {
  if (!frames_.count(label)) return;
  selected_ = label;
  markChanged();
  const Structure* st = dataset_.findStructureByLabel(label);
  event({{"event", "select"}, {"label", label}, {"structure", st ? st->id : ""}});
}

void DesktopApp::clickAt(double x, double y) {
  if (study_->participantActive()) return;
  hoverAt(x, y);
  if (lesson_->wantsClick()) {
    // A locate answer: the structure under the cursor, and for a question with a tolerance that
    // was missed, the clicked point's weighted distance from the target (else unknown: -1).
    const Structure* st = dataset_.findStructureByLabel(hovered_);
    const auto targetId = lesson_->questionTarget();
    const Structure* target = targetId ? dataset_.findStructure(*targetId) : nullptr;
    if (lesson_->wantsClickDistance() && target && st != target && lastPickMm_) {
      FieldRequest key;
      key.label = target->label;
      key.params = wdt::answerKeyParams();
      pendingClick_ = PendingClick{st ? st->id : "", *lastPickMm_, key};
      servePendingClick();
      return;
    }
    lesson_->clicked(st ? st->id : "", -1);
    return;
  }
  if (hovered_) select(hovered_);
}

void DesktopApp::handleEvent(const SDL_Event& e) {
  ImGui_ImplSDL2_ProcessEvent(&e);
  if (e.type == SDL_QUIT) quit_ = true;
  if (e.type == SDL_WINDOWEVENT && e.window.event == SDL_WINDOWEVENT_CLOSE) quit_ = true;
  if (options_.script) return;  // scripted runs take no user input
  if (e.type == SDL_KEYDOWN && study_->participantActive() && !ImGui::GetIO().WantTextInput &&
      (e.key.keysym.sym == SDLK_a || e.key.keysym.sym == SDLK_b))
    study_->showSide(e.key.keysym.sym == SDLK_a ? 'A' : 'B');
  const bool overUi = ImGui::GetIO().WantCaptureMouse;
  switch (e.type) {
    case SDL_MOUSEBUTTONDOWN:
      if (overUi || !inView(e.button.x, e.button.y)) break;
      downX_ = lastX_ = e.button.x;
      downY_ = lastY_ = e.button.y;
      dragged_ = false;
      if (e.button.button == SDL_BUTTON_LEFT) leftDown_ = true;
      if (e.button.button == SDL_BUTTON_RIGHT || e.button.button == SDL_BUTTON_MIDDLE) panDown_ = true;
      break;
    case SDL_MOUSEBUTTONUP:
      if (e.button.button == SDL_BUTTON_LEFT && leftDown_ && !dragged_) clickAt(e.button.x, e.button.y);
      if (e.button.button == SDL_BUTTON_LEFT) leftDown_ = false;
      if (e.button.button != SDL_BUTTON_LEFT) panDown_ = false;
      break;
    case SDL_MOUSEMOTION: {
      const double dx = e.motion.x - lastX_, dy = e.motion.y - lastY_;
      if (leftDown_ || panDown_) {
        if (std::abs(e.motion.x - downX_) + std::abs(e.motion.y - downY_) > 3) dragged_ = true;
        if (leftDown_ && dragged_) camera_.orbit(-dx * 0.4, dy * 0.4);
        if (panDown_) {
          const double mmPerPixel = 2 * camera_.distanceMm * std::tan(camera_.fovYDeg * M_PI / 360) / std::max(1, winH_);
          const Vec3 right = cross(camera_.forward(), camera_.up());
          camera_.target = camera_.target - (dx * mmPerPixel) * right + (dy * mmPerPixel) * camera_.up();
        }
        lastX_ = e.motion.x;
        lastY_ = e.motion.y;
        markChanged();
      } else if (!overUi) {
        hoverAt(e.motion.x, e.motion.y);
      }
      break;
    }
    case SDL_MOUSEWHEEL:
      if (!overUi && e.wheel.y != 0) {
        camera_.zoom(std::pow(1.1, double(e.wheel.y)));
        markChanged();
      }
      break;
    default:
      break;
  }
}

// ---------------------------------------------------------------------------------------------
// Fields: what the shown structure needs, asked of the worker; the best that exists, uploaded.

bool DesktopApp::servePendingClick() {
  if (!pendingClick_) return false;
  const FieldService::Cached key = worker_->cached(pendingClick_->keyField);
  if (!key.host) {
    worker_->request(pendingClick_->keyField);  // a GPU field's host copy follows shortly
    return true;
  }
  const auto distance = wdt::answerKeyDistanceAt(*key.host, dataset_.labels.geometry, pendingClick_->pointMm);
  const PendingClick click = *std::exchange(pendingClick_, std::nullopt);
  lesson_->clicked(click.structure, distance.value_or(-1));
  return false;
}

void DesktopApp::updateFields() {
  for (FinishedField& f : worker_->takeFinished()) {
    const Structure* st = dataset_.findStructureByLabel(f.request.label);
    const std::string id = st ? st->id : std::to_string(f.request.label);
    if (!f.field && !f.deviceField) {
      message("distance field of " + id + ": " + f.message);
      if (pendingClick_ && pendingClick_->keyField.key() == f.request.key()) {  // graded as "distance unknown"
        const PendingClick click = *std::exchange(pendingClick_, std::nullopt);
        lesson_->clicked(click.structure, -1);
      }
      continue;
    }
    if (f.device.find("CPU") == std::string::npos && !f.device.empty()) gpuFields_ = true;
    if (!f.message.empty() && f.message != lastFieldWarning_) message(f.message);  // e.g. a CUDA failure
    lastFieldWarning_ = f.message;
    if (!gpuFields_ && !cpuFieldNotice_ && f.message.empty()) {
      cpuFieldNotice_ = true;
      message("No CUDA GPU: distance fields run on the " + f.device + ", coarse while hovering, full resolution at rest.");
    }
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s: field 1/%d in %.0f ms on %s", id.c_str(), f.request.params.downsample, f.ms,
                  f.device.c_str());
    fieldStatus_ = buf;
    event({{"event", "field"}, {"structure", id}, {"downsample", f.request.params.downsample}, {"ms", f.ms},
           {"device", f.device}});
  }
  // Set again below while the field wanted is still going up; every other way out leaves it off,
  // so that the loop can go idle.
  fieldUploading_ = false;
  const bool clickWaiting = servePendingClick();  // its field goes first: requests are latest-wins
  if (bare_) return;
  const std::uint16_t label = shownLabel();
  if (!label) return;
  auto fine = fieldRequest(label, 1);
  auto coarse = fieldRequest(label, coarseDownsample());
  if (!fine || !coarse) return;
  // A field is ready when its host copy or (computed on the GPU) its device copy exists; a GPU
  // field is shown from the device before its host copy (for picking) has arrived.
  const FieldService::Cached fineCached = worker_->cached(*fine);
  const bool fineReady = fineCached.ready();
  const FieldService::Cached coarseCached = fineReady ? FieldService::Cached{} : worker_->cached(*coarse);
  const bool coarseReady = coarseCached.ready();
  const bool resting = msBetween(hoverSince_, Clock::now()) > kRefineFieldAfterMs;
  if (!fineReady && !clickWaiting) {
    if (fine->key() == declinedFieldKey_ && (coarseReady || coarseDownsample() == 1))
      ;  // the user cancelled this full-resolution field: keep the coarse one
    else if (gpuFields_ || coarseDownsample() == 1 || (coarseReady && resting))
      worker_->request(*fine);
    else if (!coarseReady)
      worker_->request(*coarse);
  }
  const FieldService::Cached& chosen = fineReady ? fineCached : coarseCached;
  const auto& best = chosen.host;  // may still be missing for a GPU field
  const auto& bestDevice = chosen.device;
  const void* source = bestDevice ? static_cast<const void*>(bestDevice.get()) : static_cast<const void*>(best.get());
  const std::string key = fineReady ? fine->key() : coarse->key();
  if (source && source == fieldSource_ && key == fieldKey_ && fieldLabel_ == label) {
    if (!field_ && best) field_ = best;  // the host copy of the field shown arrived
    return;
  }
  if (!source || !renderer_) return;
  const Clock::time_point uploadStart = Clock::now();
  // A field computed on the GPU goes into the texture there (CUDA–GL interop). A host field goes
  // up a few slices per frame (software GL needs ~0.2 s for a 256³ field); the view keeps the
  // previous field until the new one is complete.
  Status uploaded = bestDevice ? renderer_->setFieldFromDevice(*bestDevice) : Status{};
  bool complete = bestDevice && uploaded;
  if (bestDevice && !uploaded) {
    message("CUDA-GL interop failed, uploading the field from host memory: " + uploaded.error().message);
    if (!best) return;  // try again when the host copy is there
  }
  if (!complete) {
    auto step = renderer_->uploadFieldStep(best->distances, kFieldUploadStepMs);
    uploaded = step ? Status{} : Status(tl::unexpected(step.error()));
    complete = step && *step;
  }
  if (recording_ && !frameLog_.empty()) frameLog_.back().uploadMs += msBetween(uploadStart, Clock::now());
  if (auto st = uploaded; !st) {
    message("uploading the field: " + st.error().message);
    return;
  }
  fieldUploading_ = !complete;
  if (!complete) return;
  renderer_->setSelected(label);
  field_ = best;
  fieldSource_ = source;
  fieldLabel_ = label;
  fieldKey_ = key;
}

// ---------------------------------------------------------------------------------------------
// Rendering with adaptive quality

void DesktopApp::renderVolume(Clock::time_point frameStart) {
  if (!renderer_ || !texture_) return;
  const std::string key = stateKey();
  const Clock::time_point now = Clock::now();
  if (key != renderedKey_) {
    // Something changed: render at the finest level whose predicted cost fits the budget.
    int level = 0;
    if (msPerUnit_ > 0) {
      for (int l = kFullLevel; l >= 0; --l) {
        const render::RenderSettings s = viewSettings(l);
        const double units = double(s.width) * double(s.height) / kLevels[l].stepFactor;
        if (msPerUnit_ * units <= kInteractionBudgetMs) {
          level = l;
          break;
        }
      }
    }
    // A change that is not an interaction (a field arriving, a script action) after a rest
    // still starts coarse: it is refined over the next frames.
    interacting_ = true;
    markChanged();
    renderedLevel_ = level - 1;
  } else if (renderedLevel_ >= kFullLevel || msBetween(lastChange_, now) < kRestAfterMs) {
    interacting_ = renderedLevel_ < kFullLevel && msBetween(lastChange_, now) < kRestAfterMs;
    return;  // nothing new to show, or the user is still moving: keep the image
  } else {
    interacting_ = false;
    // Within the frame budget unless full quality is asked for (the checkbox, or a scripted
    // screenshot outside a measured sweep).
    const bool capped = !fullAtRest_ && (!options_.script || recording_);
    if (capped && msPerUnit_ > 0) {
      const render::RenderSettings next = viewSettings(renderedLevel_ + 1);
      if (msPerUnit_ * double(next.width) * double(next.height) / kLevels[renderedLevel_ + 1].stepFactor >
          options_.frameBudgetMs) {
        renderedKey_ = key;
        restCapped_ = true;
        return;
      }
    }
  }
  restCapped_ = false;
  int level = std::min(kFullLevel, renderedLevel_ + 1);
  if (!interacting_ && msPerUnit_ > 0)  // at rest: skip levels that would be cheap but still coarse
    while (level < kFullLevel) {
      const render::RenderSettings next = viewSettings(level + 1);
      if (msPerUnit_ * double(next.width) * double(next.height) / kLevels[level + 1].stepFactor > kRefineBudgetMs) break;
      ++level;
    }
  render::RenderSettings s = viewSettings(level);
  const std::uint16_t label = bare_ ? shownLabel() : (fieldLabel_ ? fieldLabel_ : shownLabel());
  renderer_->setSelected(label);
  if (bare_ || !fieldSource_) s.preset.mode = render::RenderMode::Bare;
  const Clock::time_point start = Clock::now();
  auto image = renderer_->render(s);
  if (!image) {
    message("rendering: " + image.error().message);
    renderedKey_ = key;
    renderedLevel_ = kFullLevel;
    return;
  }
  const double ms = msBetween(start, Clock::now());
  const double units = double(s.width) * double(s.height) / kLevels[level].stepFactor;
  msPerUnit_ = msPerUnit_ > 0 ? 0.7 * msPerUnit_ + 0.3 * ms / units : ms / units;
  if (auto st = texture_->upload(*image); !st) message(st.error().message);
  renderedKey_ = key;
  renderedLevel_ = level;
  if (recording_ && !frameLog_.empty()) {
    frameLog_.back().level = level;
    frameLog_.back().renderMs = ms;
  }
  (void)frameStart;
}

// ---------------------------------------------------------------------------------------------
// The panels

void DesktopApp::buildUi() {
  const float panelW = 320 * uiScale_;
  if (study_->participantActive())
    study_->drawParticipant(panelW, float(winH_));  // in place of the explore panel: no names shown
  else
    explorePanel(panelW);
  study_->drawCoordinator(panelW + 20, 20);
  if (study_->participantActive()) {
    import_->poll();  // the participant sees no other window, and the trial's dataset stays
  } else {
    import_->draw(panelW + 40, 40);
    if (auto imported = import_->takeDatasetToOpen()) {
      const std::string id = imported->id;
      if (auto st = showDataset(std::move(*imported), "", ""); !st) message("opening '" + id + "': " + st.error().message);
    }
  }
  if (texture_ && texture_->handle()) {
    ImGui::GetBackgroundDrawList()->AddImage(reinterpret_cast<ImTextureID>(texture_->handle()), ImVec2(panelW, 0),
                                             ImVec2(float(winW_), float(winH_)));
  }
  if (!study_->participantActive() && expertOn() &&
      expert_->draw(float(winW_) - 340 * uiScale_, 340 * uiScale_, float(winH_)))
    syncExpert();
  if (!renderer_) {
    ImGui::GetBackgroundDrawList()->AddText(ImVec2(panelW + 20, 20), IM_COL32(255, 140, 120, 255),
                                            "The volume view is unavailable (see the messages on the left).");
  }
}

void DesktopApp::syncStudyView() {
  const auto shown = study_->shown();
  if (!shown) return;
  if (expertOn()) setExpert(false);  // the trial's presets, not an edited one
  const Structure* s = dataset_.findStructure(shown->structure);
  if (!s || !frames_.count(s->label)) return;  // loadStudyPresets and the dataset disagree: view unchanged
  const bool bare = shown->preset.mode == render::RenderMode::Bare;
  presets_[{s->label, bare}] = shown->preset;
  t_ = float(shown->t);
  if (bare != bare_) {
    bare_ = bare;
    markChanged();
  }
  if (selected_ != s->label || hovered_) {
    hovered_ = 0;
    selected_ = s->label;
    setView(shown->preset.view.value_or("lateral_left"));
  }
}

void DesktopApp::explorePanel(float panelW) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(panelW, float(winH_)));
  ImGui::Begin("Explore", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoTitleBar);
  ImGui::TextUnformatted("Anatomy Tutor - Explore");
  ImGui::TextDisabled("%s", dataset_.displayName.empty() ? dataset_.id.c_str() : dataset_.displayName.c_str());
  if (ImGui::SmallButton("Studies...")) study_->openCoordinator();
  ImGui::SameLine();
  if (ImGui::SmallButton("Import...")) import_->open();
  ImGui::Separator();
  lesson_->draw(float(winH_) * 0.4f);
  ImGui::Separator();

  // While a question would be given away by a name (and throughout a quiz-only lesson), no
  // structure name is shown: not the selected or hovered one, nor the browser.
  const bool hideNames = lesson_->namesHidden();
  const Structure* selected = hideNames ? nullptr : dataset_.findStructureByLabel(selected_);
  const Structure* hovered = hideNames ? nullptr : dataset_.findStructureByLabel(hovered_);
  if (selected) {
    ImGui::TextColored(ImVec4(1, 0.75f, 0.3f, 1), "%s", selected->displayName.c_str());
    ImGui::TextDisabled("%s", selected->system.c_str());
    ImGui::PushTextWrapPos(0);
    ImGui::TextUnformatted(selected->description.c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::Text("Hover: %s", hovered ? hovered->displayName.c_str() : "-");
  ImGui::Separator();

  int mode = bare_ ? 1 : 0;
  if (ImGui::RadioButton("WDT preset", &mode, 0)) {
    bare_ = false;
    markChanged();
  }
  ImGui::SameLine();
  if (ImGui::RadioButton("Bare preset", &mode, 1)) {
    bare_ = true;
    markChanged();
  }
  if (ImGui::SliderFloat("t (context)", &t_, 0, 1, "%.2f")) markChanged();
  if (ImGui::Checkbox("Full quality at rest", &fullAtRest_)) markChanged();
  ImGui::SameLine();
  if (bool on = expertOn(); ImGui::Checkbox("Expert", &on)) setExpert(on);
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Off: the view at rest stays within %.0f ms per frame (coarser on slow GL)", options_.frameBudgetMs);

  ImGui::TextUnformatted("View");
  const char* views[] = {"anterior", "posterior", "lateral_left", "lateral_right", "superior", "inferior"};
  const char* labels[] = {"Ant", "Post", "L", "R", "Sup", "Inf"};
  for (int i = 0; i < 6; ++i) {
    if (i) ImGui::SameLine();
    if (ImGui::SmallButton(labels[i])) setView(views[i]);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", views[i]);
  }
  if (ImGui::Checkbox("Clipping plane", &clipOn_)) markChanged();
  if (clipOn_) {
    const char* axes[] = {"left-right", "anterior-posterior", "inferior-superior"};
    if (ImGui::Combo("axis", &clipAxis_, axes, 3)) markChanged();
    if (ImGui::Checkbox("flip side", &clipFlip_)) markChanged();
    const float range = float(std::max(5.0, camera_.distanceMm));
    if (ImGui::SliderFloat("offset mm", &clipOffsetMm_, -range, range, "%.1f")) markChanged();
  }
  ImGui::Separator();

  if (!hideNames) ImGui::InputTextWithHint("##search", "search structures", search_, sizeof search_);
  const std::string query = str::lower(search_);
  ImGui::BeginChild("structures", ImVec2(0, -statusHeight()), true);
  if (hideNames) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextDisabled("(structure names are hidden during the question)");
    ImGui::PopTextWrapPos();
  }
  for (const auto& [system, list] : bySystem_) {
    if (hideNames) break;
    std::vector<const Structure*> shown;
    for (const Structure* s : list)
      if (query.empty() || str::lower(s->displayName).find(query) != std::string::npos ||
          str::lower(s->id).find(query) != std::string::npos || str::lower(s->description).find(query) != std::string::npos)
        shown.push_back(s);
    if (shown.empty()) continue;
    ImGui::SetNextItemOpen(true, ImGuiCond_Once);
    if (!query.empty()) ImGui::SetNextItemOpen(true);
    if (ImGui::TreeNode(system.c_str())) {
      for (const Structure* s : shown) {
        if (ImGui::Selectable(s->displayName.c_str(), s->label == selected_)) select(s->label);
        if (ImGui::IsItemHovered() && !s->description.empty()) {
          ImGui::BeginTooltip();
          ImGui::PushTextWrapPos(ImGui::GetFontSize() * 25);
          ImGui::TextUnformatted(s->description.c_str());
          ImGui::PopTextWrapPos();
          ImGui::EndTooltip();
        }
      }
      ImGui::TreePop();
    }
  }
  ImGui::EndChild();

  const double lastMs = frameLog_.empty() ? 0 : frameLog_.back().ms;
  ImGui::TextDisabled("frame %.0f ms, level %d/%d%s", lastMs, std::max(0, renderedLevel_), kFullLevel,
                      interacting_ ? " (moving)" : "");
  fieldProgress();
  ImGui::PushTextWrapPos(0);
  ImGui::TextDisabled("%s", glDescription_.c_str());
  for (const std::string& m : messages_) ImGui::TextColored(ImVec4(1, 0.5f, 0.4f, 1), "%s", m.c_str());
  ImGui::PopTextWrapPos();
  ImGui::End();
}

float DesktopApp::statusHeight() const {
  // The status lines, the GL description (two lines) and the messages as they wrap, so that the
  // messages stay visible; at most half of what is left for the structure list and them.
  float height = ImGui::GetTextLineHeightWithSpacing() * 5.5f;
  const float wrap = ImGui::GetContentRegionAvail().x;
  for (const std::string& m : messages_)
    height += ImGui::CalcTextSize(m.c_str(), nullptr, false, wrap).y + ImGui::GetStyle().ItemSpacing.y;
  return std::min(height, std::max(ImGui::GetTextLineHeightWithSpacing() * 5.5f, ImGui::GetContentRegionAvail().y * 0.5f));
}

void DesktopApp::fieldProgress() {
  const auto running = worker_->running();
  if (!running || running->elapsedMs < 250) {  // quick fields need no bar
    if (!declinedFieldKey_.empty() && !running) {
      ImGui::TextDisabled("full resolution cancelled");
      ImGui::SameLine();
      if (ImGui::SmallButton("Compute it")) declinedFieldKey_.clear();
    } else {
      ImGui::TextDisabled("%s", worker_->busy() ? "computing a distance field..." : fieldStatus_.c_str());
    }
    return;
  }
  const int ds = running->request.params.downsample;
  char text[200];
  std::snprintf(text, sizeof text, "%s field: pass %d/%d, %.1f s", ds == 1 ? "full-res" : ("1/" + std::to_string(ds)).c_str(),
                running->passesDone, running->passesPlanned, running->elapsedMs / 1000);
  const float fraction = float(running->passesDone) / float(std::max(1, running->passesPlanned));
  ImGui::ProgressBar(fraction, ImVec2(ds == 1 ? -60 * uiScale_ : -1, 0), text);
  if (ds == 1) {
    ImGui::SameLine();
    if (ImGui::SmallButton("Cancel##field")) cancelFineField();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Stop the full-resolution field; the coarse one stays on screen");
  }
}

void DesktopApp::cancelFineField() {
  const auto running = worker_->running();
  if (!running || running->request.params.downsample != 1) return;
  declinedFieldKey_ = running->request.key();
  worker_->cancelAll();
  const Structure* st = dataset_.findStructureByLabel(running->request.label);
  event({{"event", "field_cancelled"}, {"structure", st ? st->id : ""}, {"downsample", 1},
         {"passes_done", running->passesDone}, {"passes_planned", running->passesPlanned},
         {"elapsed_ms", running->elapsedMs}});
}

// ---------------------------------------------------------------------------------------------
// Scripted mode

bool DesktopApp::settled() {
  if (!renderer_) return true;
  if (renderedKey_ != stateKey() || (renderedLevel_ < kFullLevel && !restCapped_)) return false;
  if (bare_) return true;
  const std::uint16_t label = shownLabel();
  auto fine = fieldRequest(label, 1);
  if (fine && fine->key() == declinedFieldKey_) {  // the user cancelled it: the coarse field is final
    auto coarse = fieldRequest(label, coarseDownsample());
    return coarse && fieldLabel_ == label && fieldKey_ == coarse->key();
  }
  return fine && fieldLabel_ == label && fieldKey_ == fine->key();
}

void DesktopApp::setExpert(bool on) {
  if (!on) {
    expert_->stop();
  } else {
    const std::uint16_t label = shownLabel();
    render::Preset p = presetOf(label, bare_);
    p.t = t_;
    const Structure* s = dataset_.findStructureByLabel(label);
    expert_->start(p, s ? s->id : std::string());
  }
  markChanged();
}

void DesktopApp::syncExpert() {
  bare_ = expert_->preset().mode == render::RenderMode::Bare;
  t_ = expert_->preset().t;
  markChanged();
}

int DesktopApp::finishScript(int status) {
  scriptStatus_ = status;
  quit_ = true;
  return status;
}

bool DesktopApp::stepScript() {
  if (!options_.script) return true;
  if (screenshotPending_) return false;
  const Clock::time_point now = Clock::now();
  while (!actions_.empty()) {
    json& a = actions_.front();
    if (!a.is_object() || !a.contains("do") || !a["do"].is_string()) {
      message("ui script: every action must be an object with a \"do\" string, got " + a.dump());
      finishScript(2);
      return true;
    }
    const std::string what = a["do"];
    if (!actionStarted_) {
      actionStarted_ = true;
      actionStart_ = now;
    }
    const auto done = [&] {
      actions_.pop_front();
      actionStarted_ = false;
    };
    const auto structureArg = [&]() -> const Structure* {
      const std::string id = a.value("structure", "");
      const Structure* s = dataset_.findStructure(id);
      if (!s) {
        message("ui script: no structure '" + id + "' in dataset '" + dataset_.id + "'");
        finishScript(2);
      }
      return s;
    };
    try {
      if (auto r = study_->scriptAction(what, a)) {  // study_* and coordinator_* actions
        if (!*r) {
          message(r->error().message);
          finishScript(2);
          return true;
        }
        if (!**r) return false;  // still running (an export)
        done();
      } else if (auto r = import_->scriptAction(what, a)) {  // import, cancel_import, open_imported
        if (!*r) {
          message(r->error().message);
          finishScript(2);
          return true;
        }
        if (!**r) return false;  // still running
        done();
      } else if (what == "cancel_field") {
        // Waits for a full-resolution field to be computing, then cancels it as the button does.
        const auto running = worker_->running();
        if (!running || running->request.params.downsample != 1) {
          if (msBetween(actionStart_, now) > a.value("timeout_ms", 60000.0)) {
            message("ui script: cancel_field: no full-resolution field was computing");
            finishScript(1);
            return true;
          }
          return false;
        }
        cancelFineField();
        done();
      } else if (what == "select") {
        const Structure* s = structureArg();
        if (!s) return true;
        setHovered(0);
        select(s->label);
        done();
      } else if (what == "t") {
        t_ = std::clamp(a.at("value").get<float>(), 0.0f, 1.0f);
        markChanged();
        done();
      } else if (what == "mode") {
        const std::string m = a.at("value");
        if (m != "wdt" && m != "bare") {
          message("ui script: mode must be \"wdt\" or \"bare\", got \"" + m + "\"");
          finishScript(2);
          return true;
        }
        bare_ = m == "bare";
        markChanged();
        done();
      } else if (what == "view") {
        if (!render::parseNamedView(a.at("value").get<std::string>())) {
          message("ui script: unknown view " + a.at("value").dump());
          finishScript(2);
          return true;
        }
        setView(a.at("value"));
        done();
      } else if (what == "hover") {
        hoverAt(a.at("x").get<double>(), a.at("y").get<double>());
        done();
      } else if (what == "click") {
        // A locate answer off its target is graded once its distance field is there.
        if (!a.value("_clicked", false)) {
          a["_clicked"] = true;
          clickAt(a.at("x").get<double>(), a.at("y").get<double>());
        }
        if (pendingClick_) return false;
        done();
      } else if (what == "hover_structure") {
        const Structure* s = structureArg();
        if (!s) return true;
        auto p = projectStructure(s->label);
        if (!p) {
          event({{"event", "hover_structure"}, {"structure", s->id}, {"visible", false}});
        } else {
          event({{"event", "hover_structure"}, {"structure", s->id}, {"visible", true}, {"x", (*p)[0]}, {"y", (*p)[1]}});
          hoverAt((*p)[0], (*p)[1]);
        }
        done();
      } else if (LessonPanel::handled(what)) {  // lesson_user, lessons, lesson, lesson_next, answer, review, lesson_close
        auto st = lesson_->scriptAction(what, a);
        if (!st) {
          message("ui script: action " + a.dump() + ": " + st.error().message);
          finishScript(2);
          return true;
        }
        if (!*st) return false;  // a lesson still being prepared
        done();
      } else if (what == "click_structure") {
        const Structure* s = structureArg();
        if (!s) return true;
        if (!a.value("_clicked", false)) {
          a["_clicked"] = true;
          auto p = projectStructure(s->label);
          event({{"event", "click_structure"}, {"structure", s->id}, {"visible", p.has_value()}});
          if (p) clickAt((*p)[0], (*p)[1]);
        }
        if (pendingClick_) return false;
        done();
      } else if (what == "orbit") {
        camera_.orbit(a.value("azimuth", 0.0), a.value("elevation", 0.0));
        markChanged();
        done();
      } else if (what == "zoom") {
        camera_.zoom(a.at("factor").get<double>());
        markChanged();
        done();
      } else if (what == "clip") {
        clipOn_ = a.value("on", true);
        clipAxis_ = std::clamp(a.value("axis", 0), 0, 2);
        clipFlip_ = a.value("flip", false);
        clipOffsetMm_ = a.value("offset", 0.0f);
        markChanged();
        done();
      } else if (what == "wait") {
        if (msBetween(actionStart_, now) < a.value("ms", 0.0)) return false;
        done();
      } else if (what == "wait_field") {
        if (!settled()) {
          if (msBetween(actionStart_, now) > a.value("timeout_ms", 120000.0)) {
            message("ui script: wait_field timed out");
            finishScript(1);
            return true;
          }
          return false;
        }
        done();
      } else if (what == "screenshot") {
        screenshotPath_ = a.at("path");
        screenshotPending_ = true;
        done();
        return false;
      } else if (what == "record") {
        recording_ = a.value("on", true);
        if (recording_) {
          frameLog_.clear();
          latencies_.clear();
        }
        done();
      } else if (what == "hover_sweep") {
        // Hovers each visible structure's projected centroid in turn and rests `dwell_ms` on it.
        const double dwell = a.value("dwell_ms", 1200.0);
        std::deque<json> sweep;
        sweep.push_back({{"do", "record"}, {"on", true}});
        for (const auto& [system, list] : bySystem_)
          for (const Structure* s : list) {
            sweep.push_back({{"do", "hover_structure"}, {"structure", s->id}});
            sweep.push_back({{"do", "wait"}, {"ms", dwell}});
          }
        sweep.push_back({{"do", "report"}, {"out", a.value("out", "")}});
        done();
        actions_.insert(actions_.begin(), sweep.begin(), sweep.end());
      } else if (what == "expert") {
        setExpert(a.value("on", true));
        done();
      } else if (TfEditorPanel::handled(what)) {
        if (!expertOn()) setExpert(true);
        if (auto st = expert_->scriptAction(what, a); !st) {
          message("ui script: action " + a.dump() + ": " + st.error().message);
          finishScript(2);
          return true;
        }
        syncExpert();
        done();
      } else if (what == "report") {
        std::vector<double> all, moving, rest, uploads, renders;
        std::map<int, int> perLevel;
        int overBudget = 0;
        for (const FrameRecord& f : frameLog_) {
          if (f.uploadMs > 0) uploads.push_back(f.uploadMs);
          if (f.level >= 0) renders.push_back(f.renderMs);
          if (f.ms > options_.frameBudgetMs) ++overBudget;
          all.push_back(f.ms);
          (f.interacting ? moving : rest).push_back(f.ms);
          perLevel[f.level]++;
        }
        json levels = json::object();
        for (const auto& [l, n] : perLevel) levels[l < 0 ? "reused" : std::to_string(l)] = n;
        json r = {{"event", "report"},
                  {"frames", all.size()},
                  {"frame_ms_p50", percentile(all, 50)},
                  {"frame_ms_p99", percentile(all, 99)},
                  {"frame_ms_max", all.empty() ? 0 : *std::max_element(all.begin(), all.end())},
                  {"moving_frames", moving.size()},
                  {"moving_ms_p99", percentile(moving, 99)},
                  {"rest_frames", rest.size()},
                  {"rest_ms_p99", percentile(rest, 99)},
                  {"frames_per_level", levels},
                  {"field_uploads", uploads.size()},
                  {"field_upload_ms_max", uploads.empty() ? 0 : *std::max_element(uploads.begin(), uploads.end())},
                  {"frame_budget_ms", options_.frameBudgetMs},
                  {"frames_over_budget", overBudget},
                  {"renders", renders.size()},
                  {"render_ms_p50", percentile(renders, 50)},
                  {"render_ms_max", renders.empty() ? 0 : *std::max_element(renders.begin(), renders.end())},
                  {"highlights", latencies_.size()},
                  {"highlight_ms_p50", percentile(latencies_, 50)},
                  {"highlight_ms_p99", percentile(latencies_, 99)},
                  {"highlight_ms_max", latencies_.empty() ? 0 : *std::max_element(latencies_.begin(), latencies_.end())},
                  {"fields_cancelled", worker_->cancelledCount()},
                  {"window", std::to_string(winW_) + "x" + std::to_string(winH_)},
                  {"gl", glDescription_}};
        event(r);
        const std::string out = a.value("out", "");
        if (!out.empty()) std::ofstream(out) << r.dump(2) << "\n";
        recording_ = false;
        done();
      } else {
        message("ui script: unknown action \"" + what + "\"");
        finishScript(2);
        return true;
      }
    } catch (const json::exception& e) {
      message("ui script: action " + a.dump() + ": " + e.what());
      finishScript(2);
      return true;
    }
  }
  // All actions done: the final screenshot once the view has settled.
  if (options_.screenshot) {
    if (!settled() && msBetween(actionStart_, now) < 120000) return false;
    screenshotPath_ = *options_.screenshot;
    options_.screenshot.reset();
    screenshotPending_ = true;
    return false;
  }
  finishScript(scriptStatus_);
  return true;
}

// ---------------------------------------------------------------------------------------------

int DesktopApp::run() {
  if (options_.script && !options_.script->empty()) {
    std::ifstream in(*options_.script);
    if (!in) return reportError(*options_.script + ": cannot open the UI script");
    json script;
    try {
      in >> script;
    } catch (const json::exception& e) {
      return reportError(*options_.script + ": not JSON (" + e.what() + ")");
    }
    if (!script.is_object() || !script.contains("actions") || !script["actions"].is_array())
      return reportError(*options_.script + ": a UI script is an object with an \"actions\" list");
    for (const json& a : script["actions"]) actions_.push_back(a);
  }
  auto session = LearningSession::open(options_.dbPath);
  if (!session) return reportError(session.error().message);
  session_ = std::move(*session);
  if (auto st = loadContent(); !st) return reportError(st.error().message);
  study_ = std::make_unique<StudyPanel>(session_->database(), library_, [this](json j) { event(std::move(j)); });
  lesson_ = std::make_unique<LessonPanel>(
      *session_, options_.userName, dataset_.id, [this](json j) { event(std::move(j)); },
      [this](const LessonPanel::Shown& shown) { showLessonStructure(shown); }, [this] { return renderState(); });
  import_ = std::make_unique<ImportPanel>(
      session_->database(), [this](json j) { event(std::move(j)); }, [this](const std::string& m) { message(m); });
  if (auto st = openGraphics(); !st) return reportError(st.error().message);
  SDL_GetWindowSize(window_->window, &winW_, &winH_);
  SDL_GL_GetDrawableSize(window_->window, &fbW_, &fbH_);
  setView(startView_);

  while (!quit_) {
    const Clock::time_point frameStart = Clock::now();
    SDL_Event e;
    const bool idle = !options_.script && (renderedLevel_ >= kFullLevel || restCapped_) && !worker_->busy() &&
                      !fieldUploading_ && renderedKey_ == stateKey();
    if (idle && SDL_WaitEventTimeout(&e, 100)) handleEvent(e);
    while (SDL_PollEvent(&e)) handleEvent(e);
    SDL_GetWindowSize(window_->window, &winW_, &winH_);
    SDL_GL_GetDrawableSize(window_->window, &fbW_, &fbH_);
    if (quit_) break;
    stepScript();
    if (quit_) break;

    const bool record = recording_;
    if (record) frameLog_.push_back({});
    syncStudyView();
    updateFields();
    renderVolume(frameStart);
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplSDL2_NewFrame();
    ImGui::NewFrame();
    buildUi();
    ImGui::Render();
    render::gl::beginWindowFrame(fbW_, fbH_, {0.04f, 0.04f, 0.05f, 1.0f});
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (screenshotPending_) {
      screenshotPending_ = false;
      auto image = render::gl::readWindow(fbW_, fbH_);
      Status st = image ? writePng(screenshotPath_, render::toRgb(*image)) : Status(tl::unexpected(image.error()));
      if (!st) {
        message(st.error().message);
        finishScript(1);
      } else {
        event({{"event", "screenshot"}, {"path", screenshotPath_}, {"width", fbW_}, {"height", fbH_}});
      }
    }
    SDL_GL_SwapWindow(window_->window);
    render::gl::finishGl();
    const Clock::time_point end = Clock::now();
    // Highlight latency: hover onto a structure → the first frame showing its context.
    if (pendingHighlight_ && renderedKey_ == stateKey() &&
        (bare_ ? shownLabel() == pendingHighlight_->first : fieldLabel_ == pendingHighlight_->first)) {
      if (recording_) latencies_.push_back(msBetween(pendingHighlight_->second, end));
      pendingHighlight_.reset();
    }
    if (record && !frameLog_.empty()) {
      frameLog_.back().ms = msBetween(frameStart, end);
      frameLog_.back().interacting = interacting_;
    }
    if (options_.maxFps > 0)
      std::this_thread::sleep_until(frameStart + std::chrono::duration_cast<Clock::duration>(
                                                     std::chrono::duration<double>(1.0 / options_.maxFps)));
  }
  worker_->cancelAll();
  return scriptStatus_;
}

}  // namespace

int runDesktop(const std::vector<std::string>& argv) {
  auto args = cli::Args::parse(argv, {"dataset", "ui-script", "screenshot", "render-scale", "frame-budget", "max-fps"}, {});
  if (!args) return reportError("desktop: " + args.error().message, 2);
  if (args->has("help")) {
    std::printf(
        "usage: anatomy-tutor [desktop] [--dataset D] [--ui-script FILE.json [--screenshot OUT.png]] [--size WxH]\n"
        "                             [--render-scale S] [--frame-budget MS] [--max-fps N] [--db PATH] [--user NAME]\n"
        "  Opens the desktop app on the default course (explore: hover to highlight, click to select).\n"
        "  --dataset    phantom, phantom:N, a dataset imported into --db, or a volume file or DICOM folder\n"
        "               (default: the default course's dataset)\n"
        "  --ui-script  replay {\"actions\": [...]} (select, t, mode, view, hover, hover_structure, click,\n"
        "               click_structure, orbit, zoom, clip, wait, wait_field, screenshot,\n"
        "               hover_sweep, record, report; expert, tf_add_point, tf_move_point,\n"
        "               tf_delete_point, tf_colour, preset_set, preset_save; study_start, study_toggle,\n"
        "               study_rate, study_comment, study_next, study_close, coordinator_open,\n"
        "               coordinator_export, coordinator_summary; lesson_user, lessons, lesson,\n"
        "               lesson_next, answer, review, lesson_close; import, cancel_import,\n"
        "               open_imported, cancel_field)\n"
        "  --db         the database: imported datasets, presets saved in the expert panel, studies,\n"
        "               lesson progress (default: the user's)\n"
        "  --user       whose lesson progress to show and record (default: student; the same name as\n"
        "               `anatomy-tutor play --user` shares the progress; created when new)\n"
        "  --screenshot save the window as PNG once the script has run and the view has settled\n"
        "  --size       window size in logical pixels (default 1280x720)\n"
        "  --render-scale  resolution of the full-quality volume image, 0.1..1 (default 1; software GL: less)\n"
        "  --frame-budget  at rest, finer images predicted to take longer are not rendered (default 100 ms;\n"
        "               scripted screenshots and the 'Full quality at rest' box render full quality anyway)\n"
        "  --max-fps    start frames at most N times a second (scripted runs swap without vsync and\n"
        "               otherwise draw as fast as they can; 60 measures them as on a 60 Hz display)\n"
        "  --db, --user and --size may also stand before the command.\n");
    return 0;
  }
  if (!args->positional().empty()) return reportError("desktop: unexpected argument '" + args->positional()[0] + "' (see --help)", 2);
  DesktopApp::Options options;
  options.dataset = args->valueOr("dataset", "");
  options.script = args->value("ui-script");
  options.screenshot = args->value("screenshot");
  options.dbPath = args->db();
  if (auto user = args->user()) options.userName = *user;
  if (auto size = args->size()) {
    if (size->width < 400 || size->height < 300) return reportError("desktop: --size must be WxH, at least 400x300", 2);
    options.width = size->width;
    options.height = size->height;
  }
  auto frameBudget = args->number("frame-budget", options.frameBudgetMs);
  if (!frameBudget || !(*frameBudget >= 10 && *frameBudget <= 100000))
    return reportError("desktop: --frame-budget must be a number of milliseconds in 10..100000", 2);
  options.frameBudgetMs = *frameBudget;
  auto maxFps = args->number("max-fps", options.maxFps);
  if (!maxFps || !(*maxFps == 0 || (*maxFps >= 1 && *maxFps <= 1000)))
    return reportError("desktop: --max-fps must be a number in 1..1000", 2);
  options.maxFps = *maxFps;
  auto renderScale = args->number("render-scale", options.renderScale);
  if (!renderScale || !(*renderScale >= 0.1 && *renderScale <= 1))
    return reportError("desktop: --render-scale must be a number in 0.1..1", 2);
  options.renderScale = *renderScale;
  if (options.screenshot && !options.script) options.script = std::string();  // the default view
  if (!displayAvailable()) return reportError("desktop: no display (none named in DISPLAY/WAYLAND_DISPLAY, or it cannot be opened)");
  return DesktopApp(options).run();
}

}  // namespace at::app
