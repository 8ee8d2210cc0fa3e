#include "course_views.h"

#include <algorithm>
#include <filesystem>

#include "db/preset_store.h"
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
  if (!presetId.empty() && fs::is_regular_file(library.dir() / (presetId + ".json"))) return library.load(presetId);
  const bool bare = presetId.size() >= 5 && presetId.substr(presetId.size() - 5) == "_bare";
  return render::presetOrDerived(library, structureId, bare ? render::RenderMode::Bare : render::RenderMode::Wdt,
                                 levels);
}

}  // namespace at::app
