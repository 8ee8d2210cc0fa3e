// The desktop's rows of outside words (ui/list_rows.h), clicked with the mouse in a real Dear ImGui
// context without a window: every row can be clicked — and only that row answers — however many
// rows say the same words (two courses called "Skull", two labels named "bone"), and words with
// ImGui's id marker "##" are rows like any other.
#include <doctest/doctest.h>

#include <imgui.h>

#include <functional>
#include <random>
#include <string>
#include <vector>

#include "test_support.h"
#include "ui/list_rows.h"

using namespace at;

namespace {

// An ImGui context of its own, with its font atlas built, drawing into a 600 × 900 display.
class HeadlessImGui {
 public:
  HeadlessImGui() : context_(ImGui::CreateContext()) {
    ImGuiIO& io = ImGui::GetIO();
    io.DisplaySize = ImVec2(600, 900);
    io.DeltaTime = 1.0f / 60;
    io.IniFilename = nullptr;
    unsigned char* pixels = nullptr;
    int width = 0, height = 0;
    io.Fonts->GetTexDataAsRGBA32(&pixels, &width, &height);
  }
  ~HeadlessImGui() { ImGui::DestroyContext(context_); }
  HeadlessImGui(const HeadlessImGui&) = delete;
  HeadlessImGui& operator=(const HeadlessImGui&) = delete;

  // One frame with the mouse at `mouse`, its left button down or up; `draw` draws the rows in a
  // window that fills the display.
  void frame(ImVec2 mouse, bool down, const std::function<void()>& draw) {
    ImGuiIO& io = ImGui::GetIO();
    io.MousePos = mouse;
    io.MouseDown[0] = down;
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(0, 0));
    ImGui::SetNextWindowSize(io.DisplaySize);
    ImGui::Begin("rows");
    draw();
    ImGui::End();
    ImGui::Render();
  }

 private:
  ImGuiContext* context_;
};

enum class RowKind { Selectable, Checkbox };

// Draws `words` as rows of `kind` and clicks each row in turn at its centre; for each click, the
// rows that answered (clicked, or toggled).
std::vector<std::vector<int>> clickEachRow(const std::vector<std::string>& words, RowKind kind) {
  HeadlessImGui gui;
  std::vector<ImVec2> centres(words.size());
  std::vector<bool> on(words.size(), false);
  std::vector<int> answered;
  const auto draw = [&] {
    for (int i = 0; i < int(words.size()); ++i) {
      bool hit = false;
      if (kind == RowKind::Selectable) {
        hit = app::listRowSelectable(i, words[std::size_t(i)], false);
      } else {
        bool state = on[std::size_t(i)];
        hit = app::listRowCheckbox(i, words[std::size_t(i)], &state);
        on[std::size_t(i)] = state;
      }
      const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
      centres[std::size_t(i)] = ImVec2(a.x + std::min(8.0f, (b.x - a.x) / 2), (a.y + b.y) / 2);
      if (hit) answered.push_back(i);
    }
  };
  gui.frame(ImVec2(-100, -100), false, draw);
  gui.frame(ImVec2(-100, -100), false, draw);
  std::vector<std::vector<int>> out;
  for (std::size_t row = 0; row < words.size(); ++row) {
    answered.clear();
    const ImVec2 at = centres[row];
    for (const bool down : {false, false, true, true, false, false}) gui.frame(at, down, draw);
    out.push_back(answered);
  }
  return out;
}

}  // namespace

TEST_CASE("DesktopListRows_EveryRowAnswersItsOwnClick_WhateverTheWords") {
  const std::uint64_t seed = test::freshSeed("DesktopListRows");
  std::mt19937_64 rng(seed);
  const std::vector<std::string> pool = {"Skull", "Skull", "bone", "A##B", "##", "Ear\ncanal", "", "The skull on CT"};
  std::vector<std::vector<std::string>> lists = {
      {"Skull", "Skull"}, {"bone", "bone", "bone"}, {"A##B", "A##C", "A"}, {"The skull on CT", "Jaw tour"}};
  for (int n = 0; n < 6; ++n) {
    std::vector<std::string> words(std::uniform_int_distribution<std::size_t>(2, 9)(rng));
    for (std::string& w : words) w = pool[std::uniform_int_distribution<std::size_t>(0, pool.size() - 1)(rng)];
    lists.push_back(words);
  }
  for (const RowKind kind : {RowKind::Selectable, RowKind::Checkbox}) {
    for (const auto& words : lists) {
      CAPTURE(int(kind));
      CAPTURE(seed);
      std::string shown;
      for (const std::string& w : words) shown += "[" + w + "]";
      CAPTURE(shown);
      const auto answered = clickEachRow(words, kind);
      for (std::size_t row = 0; row < words.size(); ++row) {
        CAPTURE(row);
        CHECK(answered[row] == std::vector<int>{int(row)});
      }
    }
  }
}
