// The default course and its first lesson's views, and a lesson step's preset: what the desktop
// app, its no-display fallback and the explore state share.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "lessons/curriculum.h"
#include "render/camera.h"
#include "render/render_settings.h"
#include "render/derived_preset.h"
#include "render/picture_scale.h"
#include "render/preset.h"
#include "render/scene.h"
#include "volume/grid.h"
#include "core/error.h"

namespace at::db {
class Database;
}

namespace at::app {

// The default course: temporal_bone.json in the course folder (learning_session.h), else the
// first course file there by name.
Result<lessons::Course> loadDefaultCourse();
// The course the app starts on: `courseId`'s file in the course folder (an error naming the ids
// there when none has it), or the default course when `courseId` is empty.
Result<lessons::Course> loadStartCourse(const std::string& courseId);

// The show steps of the course's first lesson, in order (the default lesson's views).
std::vector<lessons::ShowStep> firstLessonViews(const lessons::Course& course);

// The step's preset: `presetId` from the database's presets when `database` is given and has it (an
// imported course's, or one the course editor captured), else the library's `presetId` if it
// exists, else the structure's shipped preset for the mode the id ends in ("_bare" → bare,
// otherwise wdt), else one derived from the data's levels.
Result<render::Preset> presetForStep(const render::PresetLibrary& library, const std::string& structureId,
                                     const std::string& presetId, const render::IntensityLevels& levels,
                                     db::Database* database = nullptr);

// A step's free camera and clipping plane as the renderer takes them (the course reader checked
// both, so these conversions cannot fail for a stored step), and back from what a view shows.
render::Camera cameraOf(const lessons::StepCamera& camera);
render::ClipPlane clipOf(const lessons::StepClip& clip);
lessons::StepCamera stepCameraOf(const render::Camera& camera);
// Error when the plane's normal is not along one patient axis (the course schema's rule).
Result<lessons::StepClip> stepClipOf(const render::ClipPlane& plane);
// Settings framed on a step's named view, with its free camera (when it has one) and plane (when
// it has one) put in: what `play` and the default views render.
void applyStepPlacement(render::RenderSettings& settings, const std::optional<lessons::StepCamera>& camera,
                        const std::optional<lessons::StepClip>& clip);

// A step's view as every front end draws it (play and exam pictures, default views, the question
// checks; the render command and the desktop set the unit with the same render::applyFieldScale):
// framed on `request`, the step's camera and plane put in, and with a field the distance unit
// measured from that field on that very view (render/field_scale.h); without one, the
// structure's size-based unit. `picture` (the labels, structure and gradients the view is drawn
// with) lets a fuzzy or outline view's unit and a lighting view's reach be judged on its picture
// (render/picture_scale.h).
Result<render::RenderSettings> stepViewSettings(const render::Preset& preset, const render::StructureFrame& frame,
                                                const render::ViewRequest& request,
                                                const std::optional<lessons::StepCamera>& camera,
                                                const std::optional<lessons::StepClip>& clip, const FloatVolume* field,
                                                const Volume& volume, const render::PictureInputs* picture = nullptr);

}  // namespace at::app
