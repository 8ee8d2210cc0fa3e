#include "render/target_side.h"

#include "render/click_point.h"

namespace at::render {

std::vector<std::string> targetSidesToTry(const std::string& own) {
  std::vector<std::string> sides{own};
  for (NamedView v : {NamedView::LateralRight, NamedView::Superior, NamedView::Anterior, NamedView::Posterior,
                      NamedView::Inferior, NamedView::LateralLeft})
    if (toString(v) != own) sides.emplace_back(toString(v));
  return sides;
}

bool targetClickableAt(const Camera& camera, int width, int height, const LabelMap& labels, std::uint16_t targetLabel,
                       const std::optional<ClipPlane>& clip, const std::function<PickResult(double x, double y)>& pickAt) {
  const auto middle = middleOfStructure(labels, targetLabel, camera, width, height, clip);
  if (!middle) return false;
  const PickResult hit = pickAt(middle->x, middle->y);
  return hit.hit && hit.label == targetLabel;
}

Result<std::optional<std::string>> firstSideShowingTarget(
    const std::string& own, const std::function<Result<bool>(const std::string& side)>& clickableFrom) {
  for (const std::string& side : targetSidesToTry(own)) {
    auto clickable = clickableFrom(side);
    if (!clickable) return tl::unexpected(clickable.error());
    if (*clickable) return std::optional<std::string>(side);
  }
  return std::optional<std::string>();
}

}  // namespace at::render
