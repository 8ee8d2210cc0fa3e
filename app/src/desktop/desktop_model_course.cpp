// DesktopModel: the course editor's locate check (course_editor.h, LocateViewCheck) on the dataset
// on screen.
#include "desktop_model.h"

namespace at::app {

CourseEditor::LocateCheckWork DesktopModel::locateCheckWork(const quiz::Question& question,
                                                            const lessons::QuestionScene& scene,
                                                            const render::Preset& preset) {
  // The work reads the dataset's volume and gradients_ (unchanged while the dataset is shown:
  // showDataset stops a check before replacing them) and the checker's own copy of the labels and
  // structures, never the dataset's, which showEditedLabels writes while a check may run. The copy
  // is taken here, on the UI thread with no check running (the editor runs one at a time), when
  // the labels shown changed since the checker took them; the fields it kept go with them.
  if (!locateChecker_ || checkerLabelsRevision_ != editorLabelsRevision_) {
    if (!locateChecker_) locateChecker_ = std::make_unique<LocateViewChecker>(*dataset_, gradients_);
    locateChecker_->useLabels(dataset_->labels, dataset_->structures);
    checkerLabelsRevision_ = editorLabelsRevision_;
  }
  return [checker = locateChecker_.get(), question, scene, preset](const std::atomic<bool>& cancel) {
    return checker->check(question, scene, preset, &cancel);
  };
}

}  // namespace at::app
