#include "tf_editor_panel.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

#include <imgui.h>

#include "core/strings.h"
#include "db/preset_store.h"

namespace at::app {

using json = nlohmann::json;

namespace {

ImU32 colourOf(const render::Rgba& c, float alpha = 1) {
  return ImGui::ColorConvertFloat4ToU32(ImVec4(c[0], c[1], c[2], alpha));
}

render::Rgba rgbaArg(const json& a, const render::Rgba& fallback) {
  if (!a.contains("rgba")) return fallback;
  const auto v = a.at("rgba").get<std::vector<float>>();
  if (v.size() != 4) throw std::invalid_argument("\"rgba\" must be 4 numbers");
  return {v[0], v[1], v[2], v[3]};
}

}  // namespace

TfEditorPanel::TfEditorPanel(const Dataset& dataset, db::Database& database, EventSink events)
    : database_(database), events_(std::move(events)) {
  const auto& v = dataset.volume.voxels;
  if (!v.empty()) {
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    huMin_ = double(*lo);
    huMax_ = std::max(double(*hi) + 1, huMin_ + 1);
  }
  histogram_ = render::logHistogram(v, 128, huMin_, huMax_);
}

void TfEditorPanel::start(const render::Preset& base, const std::string& structure) {
  preset_ = base;
  structure_ = structure;
  active_ = true;
  dragging_.reset();
  menuFor_.reset();
  changed();
  events_({{"event", "expert"}, {"structure", structure}, {"preset", json::parse(render::presetToJson(preset_))}});
}

bool TfEditorPanel::splineEditor(const char* id, bool data, float width, float height) {
  auto& pts = points(data);
  const render::TfAxisRange range = data ? render::dataAxisRange() : render::distanceAxisRange();
  // The shown x range: the dataset's HU range (data) or 0..1, widened to hold every point.
  double x0 = data ? huMin_ : 0.0, x1 = data ? huMax_ : 1.0;
  x0 = std::min(x0, pts.front().x);
  x1 = std::max(x1, pts.back().x);
  ImGui::InvisibleButton(id, ImVec2(width, height), ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  const ImVec2 p0 = ImGui::GetItemRectMin(), p1 = ImGui::GetItemRectMax();
  const auto toPx = [&](double x, float a) {
    return ImVec2(p0.x + float((x - x0) / (x1 - x0)) * (p1.x - p0.x), p1.y - a * (p1.y - p0.y));
  };
  const ImVec2 mouse = ImGui::GetMousePos();
  const double mouseX = x0 + double((mouse.x - p0.x) / (p1.x - p0.x)) * (x1 - x0);
  const float mouseA = std::clamp((p1.y - mouse.y) / (p1.y - p0.y), 0.0f, 1.0f);

  ImDrawList* dl = ImGui::GetWindowDrawList();
  dl->AddRectFilled(p0, p1, IM_COL32(25, 25, 30, 255));
  if (data && !histogram_.empty()) {
    const float bw = (p1.x - p0.x) * float((huMax_ - huMin_) / (x1 - x0)) / float(histogram_.size());
    const float hx = toPx(huMin_, 0).x;
    for (std::size_t i = 0; i < histogram_.size(); ++i)
      if (histogram_[i] > 0)
        dl->AddRectFilled(ImVec2(hx + bw * float(i), p1.y - histogram_[i] * (p1.y - p0.y)),
                          ImVec2(hx + bw * float(i + 1), p1.y), IM_COL32(80, 80, 95, 255));
  }
  if (auto tf = render::TransferFunction1D::fromPoints(pts)) {
    const int n = std::max(2, int(width / 2));
    ImVec2 prev;
    for (int i = 0; i < n; ++i) {
      const double x = x0 + (x1 - x0) * i / (n - 1);
      const render::Rgba c = tf->evaluate(x);
      const ImVec2 q = toPx(x, c[3]);
      dl->AddLine(ImVec2(q.x, p1.y), ImVec2(q.x, p1.y - 4), colourOf(c));
      if (i) dl->AddLine(prev, q, IM_COL32(230, 230, 230, 255), 1.5f);
      prev = q;
    }
  }
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const ImVec2 q = toPx(pts[i].x, pts[i].rgba[3]);
    dl->AddCircleFilled(q, 5, colourOf(pts[i].rgba));
    dl->AddCircle(q, 5, IM_COL32(255, 255, 255, 255));
  }

  bool edited = false;
  const double xTol = 7.0 * (x1 - x0) / double(p1.x - p0.x);
  const double aTol = 7.0 / double(p1.y - p0.y);
  const auto hit = render::hitTestTfPoint(pts, mouseX, mouseA, xTol, aTol);
  const ImGuiIO& io = ImGui::GetIO();
  if (ImGui::IsItemHovered()) {
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
      if (hit && !io.KeyCtrl) {
        dragging_ = Selection{data, *hit};
      } else if (ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left) || io.KeyCtrl) {
        render::Rgba c = render::TransferFunction1D::fromPoints(pts)->evaluate(mouseX);
        c[3] = mouseA;
        if (auto i = render::addTfPoint(pts, mouseX, c, range)) {
          dragging_ = Selection{data, *i};
          edited = true;
        }
      }
    }
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Right) && hit) {
      menuFor_ = Selection{data, *hit};
      ImGui::OpenPopup(id);
    }
    if (hit) ImGui::SetTooltip("x %.3f  opacity %.2f", pts[*hit].x, double(pts[*hit].rgba[3]));
  }
  if (dragging_ && dragging_->data == data) {
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
      dragging_.reset();
    } else if (io.MouseDelta.x != 0 || io.MouseDelta.y != 0) {
      if (render::moveTfPoint(pts, dragging_->index, mouseX, mouseA, range)) edited = true;
    }
  }
  if (ImGui::BeginPopup(id)) {
    if (menuFor_ && menuFor_->data == data && menuFor_->index < pts.size()) {
      const std::size_t i = menuFor_->index;
      ImGui::Text("point %zu at x = %.3f", i, pts[i].x);
      if (ImGui::MenuItem("Delete", nullptr, false, pts.size() > 2)) {
        if (render::deleteTfPoint(pts, i)) edited = true;
        menuFor_.reset();
        ImGui::CloseCurrentPopup();
      } else {
        render::Rgba c = pts[i].rgba;
        if (ImGui::ColorPicker4("colour", c.data(), ImGuiColorEditFlags_AlphaBar) &&
            render::setTfPointColour(pts, i, c))
          edited = true;
      }
    }
    ImGui::EndPopup();
  }
  return edited;
}

bool TfEditorPanel::draw(float x, float width, float height) {
  if (!active_) return false;
  ImGui::SetNextWindowPos(ImVec2(x, 0));
  ImGui::SetNextWindowSize(ImVec2(width, height));
  ImGui::Begin("Expert", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  bool edited = false;
  const float w = ImGui::GetContentRegionAvail().x;
  ImGui::TextUnformatted("Data TF (HU; bars: log histogram)");
  edited |= splineEditor("##data_tf", true, w, 120);
  ImGui::TextUnformatted("Distance TF (normalised distance)");
  edited |= splineEditor("##distance_tf", false, w, 90);
  ImGui::TextDisabled("drag: move; double/ctrl-click: add; right-click: menu");

  ImGui::PushItemWidth(w * 0.55f);
  render::Preset& p = preset_;
  int mode = int(std::find(render::allRenderModes().begin(), render::allRenderModes().end(), p.mode) -
                 render::allRenderModes().begin());
  if (ImGui::BeginCombo("mode", render::toString(p.mode))) {
    for (std::size_t i = 0; i < render::allRenderModes().size(); ++i)
      if (ImGui::Selectable(render::toString(render::allRenderModes()[i]), int(i) == mode)) {
        p.mode = render::allRenderModes()[i];
        edited = true;
      }
    ImGui::EndCombo();
  }
  edited |= ImGui::SliderFloat("t (context)", &p.t, 0, 1, "%.2f");
  edited |= ImGui::SliderFloat("alpha f(x)", &p.alpha, 1.01f, 10, "%.2f");
  edited |= ImGui::DragFloat("lighting alpha", &p.lightingAlpha, 0.01f, 0, 100, "%.3f");
  edited |= ImGui::DragFloat("lighting beta", &p.lightingBeta, 0.01f, 0, 100, "%.3f");
  int rule = p.weightRule == "trapezoid" ? 1 : 0;
  const char* rules[] = {"entering", "trapezoid"};
  if (ImGui::Combo("weight rule", &rule, rules, 2)) {
    p.weightRule = rules[rule];
    edited = true;
  }
  std::array<float, 2> win = p.huWindow;
  if (ImGui::DragFloat2("HU window", win.data(), 5, -32768, 32767, "%.0f") && win[0] < win[1]) {
    p.huWindow = win;
    edited = true;
  }
  edited |= ImGui::DragFloat("weight base", &p.weightBase, 0.001f, 0, 10, "%.3f");
  p.lightingAlpha = std::max(0.0f, p.lightingAlpha);
  p.lightingBeta = std::max(0.0f, p.lightingBeta);
  p.weightBase = std::max(0.0f, p.weightBase);

  ImGui::Separator();
  ImGui::InputText("name", saveName_, sizeof saveName_);
  ImGui::InputTextWithHint("export", "optional: PATH.json", exportPath_, sizeof exportPath_);
  if (ImGui::Button("Save as")) {
    const std::string path = exportPath_;
    const Status st = saveAs(saveName_, path.empty() ? std::nullopt : std::optional<std::string>(path));
    saveStatus_ = st ? "saved '" + str::identifier(saveName_) + "'" : st.error().message;
  }
  ImGui::PushTextWrapPos(0);
  ImGui::TextDisabled("%s", saveStatus_.c_str());
  ImGui::PopTextWrapPos();
  ImGui::PopItemWidth();
  ImGui::End();
  if (edited) changed();
  return edited;
}

bool TfEditorPanel::handled(const std::string& what) {
  return what == "tf_add_point" || what == "tf_move_point" || what == "tf_delete_point" || what == "tf_colour" ||
         what == "preset_set" || what == "preset_save";
}

Result<bool> TfEditorPanel::tfArg(const json& a) const {
  const std::string tf = a.value("tf", "");
  if (tf == "data") return true;
  if (tf == "distance") return false;
  return fail("\"tf\" must be \"data\" or \"distance\", got \"" + tf + "\"");
}

Status TfEditorPanel::scriptAction(const std::string& what, const json& a) {
  Status st;
  try {
    if (what == "preset_save") {
      return saveAs(a.at("name").get<std::string>(),
                    a.contains("export") ? std::optional<std::string>(a.at("export").get<std::string>()) : std::nullopt);
    }
    if (what == "preset_set") {
      render::Preset p = preset_;
      if (a.contains("mode")) {
        auto m = render::parseRenderMode(a.at("mode").get<std::string>());
        if (!m) return tl::unexpected(m.error());
        p.mode = *m;
      }
      p.t = a.value("t", p.t);
      p.alpha = a.value("alpha", p.alpha);
      p.lightingAlpha = a.value("lighting_alpha", p.lightingAlpha);
      p.lightingBeta = a.value("lighting_beta", p.lightingBeta);
      p.weightRule = a.value("rule", p.weightRule);
      p.weightBase = a.value("base", p.weightBase);
      if (a.contains("hu_window")) p.huWindow = a.at("hu_window").get<std::array<float, 2>>();
      auto valid = render::parsePreset(render::presetToJson(p), "preset_set");
      if (!valid) return tl::unexpected(valid.error());
      preset_ = p;
      changed();
      return {};
    }
    auto data = tfArg(a);
    if (!data) return tl::unexpected(data.error());
    auto& pts = points(*data);
    const render::TfAxisRange range = *data ? render::dataAxisRange() : render::distanceAxisRange();
    if (what == "tf_add_point") {
      const double x = a.at("x").get<double>();
      const render::Rgba c = rgbaArg(a, render::TransferFunction1D::fromPoints(pts)->evaluate(x));
      auto i = render::addTfPoint(pts, x, c, range);
      if (!i) return tl::unexpected(i.error());
      events_({{"event", "tf_point"}, {"tf", a["tf"]}, {"index", *i}, {"x", pts[*i].x}});
    } else {
      const std::size_t index = a.at("index").get<std::size_t>();
      if (what == "tf_move_point") {
        if (index >= pts.size()) return fail("no point " + std::to_string(index));
        auto x = render::moveTfPoint(pts, index, a.value("x", pts[index].x), a.value("alpha", pts[index].rgba[3]), range);
        if (!x) return tl::unexpected(x.error());
        events_({{"event", "tf_point"}, {"tf", a["tf"]}, {"index", index}, {"x", *x}});
      } else if (what == "tf_delete_point") {
        st = render::deleteTfPoint(pts, index);
      } else {  // tf_colour
        if (index >= pts.size()) return fail("no point " + std::to_string(index));
        st = render::setTfPointColour(pts, index, rgbaArg(a, pts[index].rgba));
      }
    }
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  if (st) changed();
  return st;
}

Status TfEditorPanel::saveAs(const std::string& name, const std::optional<std::string>& exportPath) {
  const std::string id = str::identifier(name);
  if (id.empty()) return fail("save preset: the name '" + name + "' has no letters or digits");
  render::Preset p = preset_;
  p.name = name;
  p.id = id;
  if (!structure_.empty()) p.structure = structure_;
  const std::string text = render::presetToJson(p);
  auto valid = render::parsePreset(text, id);
  if (!valid) return tl::unexpected(withContext("save preset", valid.error()));
  const db::StoredPreset stored{id, p.structure, render::toString(p.mode), text};
  if (auto st = db::savePreset(database_, stored); !st) return st;
  json ev = {{"event", "preset_saved"}, {"id", id}, {"db", database_.path()}};
  if (exportPath) {
    if (auto st = render::savePreset(p, *exportPath); !st) return st;
    ev["export"] = *exportPath;
  }
  events_(ev);
  return {};
}

}  // namespace at::app
