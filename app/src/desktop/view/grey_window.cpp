#include "view/grey_window.h"

#include <algorithm>
#include <cmath>

namespace at::app {

void GreyWindow::reset(const IntensityModel& m) {
  if (m.hounsfield()) {
    centre_ = (400 - m.intercept) / m.slope;
    width_ = 2000 / m.slope;
  } else {
    centre_ = 0.5 * (m.window[0] + m.window[1]);
    width_ = std::max(1e-3, double(m.window[1] - m.window[0]));
  }
}

bool GreyWindow::drag(double dx, double dy) {
  if (dx == 0 && dy == 0) return false;
  width_ = std::clamp(width_ * std::exp(dx / 200.0), 1e-3, 1e7);
  centre_ -= dy * width_ / 256.0;
  return true;
}

void GreyWindow::applyTo(SliceRequest& request) const {
  request.windowCentreHu = centre_;
  request.windowWidthHu = width_;
}

}  // namespace at::app
