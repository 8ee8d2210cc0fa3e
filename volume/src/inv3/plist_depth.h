// How deep a property list nests, found without building it: libplist's parsers recurse once per
// level, so a few kilobytes nested 200,000 levels deep overflow the stack. Checked on the raw
// bytes (XML: element nesting; binary "bplist00": the object graph from its top object) before
// libplist sees them. main.plist nests 3 levels in the projects InVesalius writes.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "core/error.h"

namespace at::inv3 {

inline constexpr std::size_t kMaxPlistDepth = 64;

// Fine when the plist nests at most `maxDepth` containers; otherwise an Invalid error
// "<where>: the property list nests more than N levels". A malformed binary plist (references
// outside its object table, a cycle) is refused the same way: libplist would recurse on it too.
// Bytes that are neither form pass (libplist refuses them itself).
Status checkPlistDepth(std::string_view bytes, const std::string& where, std::size_t maxDepth = kMaxPlistDepth);

}  // namespace at::inv3
