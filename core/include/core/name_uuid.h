// Name-based UUIDs (RFC 4122 §4.3, version 5: SHA-1 of a namespace UUID and a name): the same
// name in the same namespace always gives the same id, and the id is one that every UUID parser
// and xAPI record store takes (version 5, variant 10xx). In target at_core_sha256 (nettle).
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace at {

// RFC 4122's namespace for names that are URLs (Appendix C).
inline constexpr std::string_view kUrlNamespaceUuid = "6ba7b811-9dad-11d1-80b4-00c04fd430c8";

// "xxxxxxxx-xxxx-5xxx-Nxxx-xxxxxxxxxxxx" in lower-case hex (N is 8, 9, a or b); nullopt when
// `namespaceUuid` is not a UUID in that textual form.
std::optional<std::string> uuidV5(std::string_view namespaceUuid, std::string_view name);

}  // namespace at
