// Presets that belong to a course. An imported package's presets are stored in the database
// under "<course id>/<preset id>" and the course's steps are rewritten to name those keys, so a
// package can never stand in for a shipped preset (data/presets/<id>.json) or another course's:
// the shipped library is only asked for safe names (core/safe_name.h), which never hold '/', and
// course ids are unique. Exporting turns the keys back into the package's plain ids.
#pragma once

#include <set>
#include <string>

#include "lessons/curriculum.h"

namespace at::app {

// "<courseId>/<presetId>".
std::string coursePresetKey(const std::string& courseId, const std::string& presetId);

// The course with every step preset in `packaged` renamed to its course key.
lessons::Course withCoursePresetKeys(lessons::Course course, const std::set<std::string>& packaged);

// The course with every "<course.id>/<id>" step preset renamed back to "<id>".
lessons::Course withoutCoursePresetKeys(lessons::Course course);

}  // namespace at::app
