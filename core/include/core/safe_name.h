// Names that come from outside the program — a course package's dataset, course and preset ids,
// `import --name`, the desktop's Import… and Open course… forms — and that become folder or file
// names, or keys other names are built from. One rule for all of them, checked before anything
// is read from or written to disk:
//
//   * 1 to kMaxSafeNameBytes (64) characters;
//   * only ASCII letters, digits, '_', '-' and '.';
//   * the first character a letter, a digit or '_' (so never '.', '..', a hidden name, or one a
//     command line would take for an option);
//   * never ending in '.' (some file systems drop it, making two names one).
//
// Unicode is refused rather than normalised: look-alike letters (Cyrillic 'а' for Latin 'a'),
// combining marks and width variants would otherwise give two names that look the same and
// name different folders. A refusal is one line naming the field and quoting the name safely.
//
// Paths under a folder the program owns (the data folder beside the database) are built only
// with confinedPath, which refuses any result that leaves that folder once symbolic links are
// resolved.
#pragma once

#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include "core/error.h"

namespace at {

inline constexpr std::size_t kMaxSafeNameBytes = 64;

// True when `name` follows the rule above.
bool isSafeName(std::string_view name);

// The rule as a Status: Invalid "<field> '<name>': <why>; <the rule>" (the name made printable).
Status checkSafeName(std::string_view field, std::string_view name);

// `base` joined with `components` (each a safe name, or a safe name with an extension such as
// "volume.nrrd" — the same rule), once the result, with every symbolic link in its existing part
// resolved, is still inside `base` (itself resolved). `base` must exist. Errors (Invalid) name
// `field` and the path; nothing is created.
Result<std::filesystem::path> confinedPath(const std::filesystem::path& base,
                                           std::initializer_list<std::string_view> components,
                                           std::string_view field);

// Whether `path` (resolved as confinedPath resolves) lies strictly inside `base` (resolved).
bool isInside(const std::filesystem::path& base, const std::filesystem::path& path);

}  // namespace at
