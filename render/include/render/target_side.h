// Turning a view so that a locate question's target can be clicked. A question asks from its own
// side; when the target is hidden from there (behind bone, outside the picture), the view turns to
// the first side of a fixed list from which it shows. The terminal's pictures (app
// cli/terminal_views.cpp) and the desktop's exam (app desktop/desktop_model_exam.cpp) both choose
// the side here, so that both show the same side for the same question.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "render/camera.h"
#include "render/render_settings.h"
#include "volume/grid.h"

namespace at::render {

// The sides tried, in order: `own` first, then lateral_right, superior, anterior, posterior,
// inferior and lateral_left, each once (`own` is not tried twice).
std::vector<std::string> targetSidesToTry(const std::string& own);

// Whether the target can be clicked in a width × height view from `camera`: a click on the middle
// of where it lies in the picture (render/click_point.h: the voxels labelled `targetLabel` in
// `labels` that `clip` keeps, projected; for a target in two parts, the middle of the wider part)
// hits `targetLabel` (`pickAt(x, y)`, in the image's pixels). False where none of it lies in the
// picture.
bool targetClickableAt(const Camera& camera, int width, int height, const LabelMap& labels, std::uint16_t targetLabel,
                       const std::optional<ClipPlane>& clip, const std::function<PickResult(double x, double y)>& pickAt);

// The first side of targetSidesToTry(own) from which `clickableFrom(side)` says the target can be
// clicked; nullopt when none can (the caller stays on `own`). An error from `clickableFrom` ends
// the search and is returned.
Result<std::optional<std::string>> firstSideShowingTarget(
    const std::string& own, const std::function<Result<bool>(const std::string& side)>& clickableFrom);

}  // namespace at::render
