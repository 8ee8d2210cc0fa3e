// The grey window of a slice picture (centre and width in the volume's stored values), as the
// desktop's slice panes show it and the user drags it: the Slices window and the segment editor's
// slice share this one model, so a drag does the same in both.
#pragma once

#include <array>

#include "volume/intensity.h"
#include "volume/slice_image.h"

namespace at::app {

class GreyWindow {
 public:
  // The intensity model's default: CT 400 ± 1000 HU (bone and soft tissue, the slice command's
  // default), plain intensities their histogram window.
  void reset(const IntensityModel& intensity);
  // A drag of (dx, dy) pixels: right/left widens/narrows the window (×e per 200 px), down/up
  // lowers/raises its centre (a 256-px drag moves it by one width). Returns whether it changed.
  bool drag(double dx, double dy);
  // Into a slice request (volume/slice_image.h).
  void applyTo(SliceRequest& request) const;
  std::array<double, 2> centreWidth() const { return {centre_, width_}; }

 private:
  double centre_ = 400, width_ = 2000;
};

}  // namespace at::app
