#include "course_presets.h"

#include <functional>

namespace at::app {

namespace {

void forEachStepPreset(lessons::Course& course, const std::function<void(std::string&)>& rename) {
  for (lessons::Lesson& lesson : course.lessons)
    for (lessons::Step& step : lesson.steps) {
      if (step.kind == lessons::StepKind::Show && !step.show.presetId.empty()) rename(step.show.presetId);
      if (step.kind == lessons::StepKind::Question && step.scene && !step.scene->presetId.empty()) rename(step.scene->presetId);
    }
}

}  // namespace

std::string coursePresetKey(const std::string& courseId, const std::string& presetId) { return courseId + "/" + presetId; }

lessons::Course withCoursePresetKeys(lessons::Course course, const std::set<std::string>& packaged) {
  const std::string id = course.id;
  forEachStepPreset(course, [&](std::string& preset) {
    if (packaged.count(preset)) preset = coursePresetKey(id, preset);
  });
  return course;
}

lessons::Course withoutCoursePresetKeys(lessons::Course course) {
  const std::string prefix = course.id + "/";
  forEachStepPreset(course, [&](std::string& preset) {
    if (preset.rfind(prefix, 0) == 0) preset = preset.substr(prefix.size());
  });
  return course;
}

}  // namespace at::app
