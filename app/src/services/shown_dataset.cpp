#include "shown_dataset.h"

#include <utility>

namespace at::app {

render::IntensityLevels prepareForViewing(Dataset& dataset) {
  const render::IntensityLevels levels = render::summariseIntensities(dataset.volume);
  render::leaveOutNonAnatomy(dataset.volume, dataset.labels, levels);
  return levels;
}

Result<ShownDataset> openDatasetForViewing(const DatasetRequest& request) {
  auto dataset = openNamedDataset(request);
  if (!dataset) return tl::unexpected(dataset.error());
  ShownDataset out{std::move(*dataset), {}};
  out.levels = prepareForViewing(out.dataset);
  return out;
}

}  // namespace at::app
