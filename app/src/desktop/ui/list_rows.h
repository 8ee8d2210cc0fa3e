// Rows of a list whose words come from outside: a course's or a lesson's title, a structure's name.
// Two rows may say the same (two courses called "Skull", two labels named "bone"): each row's
// ImGui id is its place in the list, never its words, so that every row can be clicked. (With the
// words as the id, the rows share it and a click on the second selects nothing.) The words are
// shown through printableUiText.
#pragma once

#include <string>

namespace at::app {

// A selectable row; true when it was clicked this frame.
bool listRowSelectable(int index, const std::string& words, bool selected);

// A checkbox row; true when it was toggled this frame (*on is then the new state).
bool listRowCheckbox(int index, const std::string& words, bool* on);

}  // namespace at::app
