// Where the panels drew the widgets a student must be able to see (a lesson's feedback and its
// Next button), for the UI script's "widgets" action: each one's rectangle in window pixels and the
// part of the window it could be seen in (its clip rectangle: the panel and any scrolled child
// region around it). Cleared at the start of every frame, so a widget not drawn is absent.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace at::app {

// Call right after drawing the widget (it reads ImGui's last item). `text`: the words it shows,
// reported with its rectangles when not empty.
void noteWidget(const std::string& name, const std::string& text = "");
void clearWidgetRects();
// {"frame": frames drawn so far, "widgets": {name: {"rect": [x0, y0, x1, y1], "clip": [x0, y0,
// x1, y1], "text"?: words}}} of the frame drawn last.
nlohmann::json widgetRects();

}  // namespace at::app
