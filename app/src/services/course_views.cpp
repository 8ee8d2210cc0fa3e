#include "course_views.h"

#include "core/safe_name.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "db/preset_store.h"
#include "render/field_scale.h"
#include "learning_session.h"
#include "lessons/course_json.h"

namespace at::app {

namespace fs = std::filesystem;

Result<lessons::Course> loadDefaultCourse() {
  const fs::path dir = courseDirectory();
  const fs::path preferred = dir / "temporal_bone.json";
  if (fs::is_regular_file(preferred)) return lessons::loadCourseJson(preferred);
  std::error_code ec;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  if (ec) return fail(dir.string() + ": cannot list the course folder (" + ec.message() + ")");
  if (files.empty()) return fail(dir.string() + ": no course file (*.json) in the course folder");
  std::sort(files.begin(), files.end());
  return lessons::loadCourseJson(files.front());
}

Result<lessons::Course> loadStartCourse(const std::string& courseId) {
  if (courseId.empty()) return loadDefaultCourse();
  const fs::path dir = courseDirectory();
  std::error_code ec;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.path().extension() == ".json") files.push_back(entry.path());
  if (ec) return fail(dir.string() + ": cannot list the course folder (" + ec.message() + ")");
  std::sort(files.begin(), files.end());
  std::string ids;
  for (const fs::path& file : files) {
    auto course = lessons::loadCourseJson(file);
    if (!course) continue;  // a broken file is reported where courses are listed
    if (course->id == courseId) return course;
    ids += (ids.empty() ? "" : ", ") + course->id;
  }
  return fail(ErrorKind::NotFound, "no course '" + courseId + "' in " + dir.string() + " (there: " + ids + ")");
}

std::vector<lessons::ShowStep> firstLessonViews(const lessons::Course& course) {
  std::vector<lessons::ShowStep> views;
  if (course.lessons.empty()) return views;
  for (const lessons::Step& step : course.lessons.front().steps)
    if (step.kind == lessons::StepKind::Show) views.push_back(step.show);
  return views;
}

Result<render::Preset> presetForStep(const render::PresetLibrary& library, const std::string& structureId,
                                     const std::string& presetId, const render::IntensityLevels& levels,
                                     db::Database* database) {
  if (database && !presetId.empty()) {
    auto stored = db::findPreset(*database, presetId);
    if (!stored) return tl::unexpected(stored.error());
    if (*stored) return render::parsePreset((*stored)->json, "preset '" + presetId + "' (database)");
  }
  if (!presetId.empty() && isSafeName(presetId) && fs::is_regular_file(library.dir() / (presetId + ".json")))
    return library.load(presetId);
  const bool bare = presetId.size() >= 5 && presetId.substr(presetId.size() - 5) == "_bare";
  return render::presetOrDerived(library, structureId, bare ? render::RenderMode::Bare : render::RenderMode::Wdt,
                                 levels);
}

render::Camera cameraOf(const lessons::StepCamera& camera) {
  auto c = render::Camera::looking(camera.targetMm, camera.look, camera.up, camera.distanceMm);
  return c ? *c : render::Camera{};  // the course reader refused anything `looking` would
}

render::ClipPlane clipOf(const lessons::StepClip& clip) { return render::ClipPlane{clip.normal, clip.d}; }

void applyStepPlacement(render::RenderSettings& settings, const std::optional<lessons::StepCamera>& camera,
                        const std::optional<lessons::StepClip>& clip) {
  if (camera) {
    const render::Camera framed = settings.camera;
    settings.camera = cameraOf(*camera);
    settings.camera.fovYDeg = framed.fovYDeg;
    settings.camera.orthographic = framed.orthographic;
  }
  if (clip) settings.clip = clipOf(*clip);
}

Result<render::RenderSettings> stepViewSettings(const render::Preset& preset, const render::StructureFrame& frame,
                                                const render::ViewRequest& request,
                                                const std::optional<lessons::StepCamera>& camera,
                                                const std::optional<lessons::StepClip>& clip, const FloatVolume* field,
                                                const Volume& volume, const render::PictureInputs* picture) {
  auto settings = render::settingsFor(preset, frame, request);
  if (!settings) return settings;
  applyStepPlacement(*settings, camera, clip);
  if (field) render::applyFieldScale(*settings, *field, volume, nullptr, frame, request, picture);
  return settings;
}

lessons::StepCamera stepCameraOf(const render::Camera& camera) {
  return lessons::StepCamera{camera.target, camera.forward(), camera.up(), camera.distanceMm};
}

Result<lessons::StepClip> stepClipOf(const render::ClipPlane& plane) {
  int axis = -1;
  for (int i = 0; i < 3; ++i)
    if (std::abs(plane.normal[std::size_t(i)]) > 1e-9) {
      if (axis >= 0) return fail("the clipping plane is not along one patient axis, which a course step cannot keep");
      axis = i;
    }
  if (axis < 0) return fail("the clipping plane has no normal");
  lessons::StepClip clip;
  clip.normal = {0, 0, 0};
  clip.normal[std::size_t(axis)] = plane.normal[std::size_t(axis)] > 0 ? 1 : -1;
  clip.d = plane.d / std::abs(plane.normal[std::size_t(axis)]);
  return clip;
}

}  // namespace at::app
