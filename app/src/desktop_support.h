// What the desktop app and its no-display fallback share: where presets and the default course
// live, a lesson step's preset, and whether a display exists.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "lessons/curriculum.h"
#include "render/preset.h"
#include "core/error.h"

namespace at::app {

// The default course: temporal_bone.json in the course folder (learning_session.h), else the
// first course file there by name.
Result<lessons::Course> loadDefaultCourse();

// The show steps of the course's first lesson, in order (the default lesson's views).
std::vector<lessons::ShowStep> firstLessonViews(const lessons::Course& course);

// The step's preset: the library's `presetId` if it exists, else the structure's shipped preset for
// the mode the id ends in ("_bare" → bare, otherwise wdt).
Result<render::Preset> presetForStep(const render::PresetLibrary& library, const std::string& structureId,
                                     const std::string& presetId);

// A display server to open a window on: DISPLAY (X11) or WAYLAND_DISPLAY set and non-empty.
// For measuring the app on a headless GPU machine, AT_DESKTOP_OFFSCREEN=1 with
// SDL_VIDEODRIVER=offscreen accepts SDL's offscreen driver (an EGL pbuffer, no window shown).
bool displayAvailable();

// The no-display fallback of `anatomy-tutor` without arguments: renders the default lesson's first
// three views (360×270) offscreen (EGL) into `outDir` as PNG files, printing one line per file. The built-in
// phantom is opened at 128³ so that this stays quick on two CPU cores.
int writeDefaultViews(const std::filesystem::path& outDir);


}  // namespace at::app
