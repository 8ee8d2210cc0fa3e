#include "plist_depth.h"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

namespace at::inv3 {

namespace {

Status tooDeep(const std::string& where, std::size_t maxDepth) {
  return fail(where + ": the property list nests more than " + std::to_string(maxDepth) + " levels");
}

// XML: every element that is opened and not closed at once is one level. Comments, processing
// instructions, the DOCTYPE and CDATA sections are skipped whole.
Status xmlDepth(std::string_view s, const std::string& where, std::size_t maxDepth) {
  std::size_t depth = 0, i = 0;
  const auto skipTo = [&](std::string_view end) {
    const std::size_t at = s.find(end, i);
    i = at == std::string_view::npos ? s.size() : at + end.size();
  };
  while ((i = s.find('<', i)) != std::string_view::npos) {
    if (s.compare(i, 4, "<!--") == 0) { skipTo("-->"); continue; }
    if (s.compare(i, 9, "<![CDATA[") == 0) { skipTo("]]>"); continue; }
    if (s.compare(i, 2, "<?") == 0 || s.compare(i, 2, "<!") == 0) { skipTo(">"); continue; }
    const bool closing = s.compare(i, 2, "</") == 0;
    const std::size_t end = s.find('>', i);
    if (end == std::string_view::npos) break;
    const bool selfClosing = s[end - 1] == '/';
    if (closing) {
      if (depth > 0) --depth;
    } else if (!selfClosing && ++depth > maxDepth) {
      return tooDeep(where, maxDepth);
    }
    i = end + 1;
  }
  return {};
}

std::uint64_t bigEndian(std::string_view s, std::size_t at, std::size_t bytes) {
  std::uint64_t v = 0;
  for (std::size_t k = 0; k < bytes; ++k) v = (v << 8) | static_cast<unsigned char>(s[at + k]);
  return v;
}

// Binary: the longest chain of container references from the top object (arrays, sets and
// dictionaries), walked without recursion; a reference back into the chain is a cycle.
Status binaryDepth(std::string_view s, const std::string& where, std::size_t maxDepth) {
  const auto malformed = [&](const std::string& why) { return fail(where + ": a damaged binary property list (" + why + ")"); };
  if (s.size() < 8 + 32) return malformed("shorter than its header and trailer");
  const std::size_t trailer = s.size() - 32;
  const std::size_t offsetSize = static_cast<unsigned char>(s[trailer + 6]);
  const std::size_t refSize = static_cast<unsigned char>(s[trailer + 7]);
  const std::uint64_t objects = bigEndian(s, trailer + 8, 8), top = bigEndian(s, trailer + 16, 8);
  const std::uint64_t table = bigEndian(s, trailer + 24, 8);
  if (offsetSize < 1 || offsetSize > 8 || refSize < 1 || refSize > 8) return malformed("bad integer sizes");
  if (objects == 0 || top >= objects || table > trailer || objects > (trailer - table) / offsetSize)
    return malformed("the object table lies outside the file");
  const auto offsetOf = [&](std::uint64_t object) { return bigEndian(s, std::size_t(table + object * offsetSize), offsetSize); };

  // The references a container object holds (empty for anything else); nullopt when damaged.
  const auto children = [&](std::uint64_t object) -> std::optional<std::vector<std::uint64_t>> {
    const std::uint64_t at = offsetOf(object);
    if (at < 8 || at >= trailer) return std::nullopt;
    const unsigned char marker = static_cast<unsigned char>(s[at]);
    const unsigned kind = marker >> 4;
    if (kind != 0xA && kind != 0xC && kind != 0xD) return std::vector<std::uint64_t>{};
    std::uint64_t count = marker & 0x0F, pos = at + 1;
    if (count == 0x0F) {  // the count follows as an integer object
      if (pos >= trailer || (static_cast<unsigned char>(s[pos]) >> 4) != 0x1) return std::nullopt;
      const std::size_t bytes = std::size_t(1) << (s[pos] & 0x0F);
      if (bytes > 8 || pos + 1 + bytes > trailer) return std::nullopt;
      count = bigEndian(s, std::size_t(pos + 1), bytes);
      pos += 1 + bytes;
    }
    const std::uint64_t refs = kind == 0xD ? 2 * count : count;
    if (count > trailer || refs > (trailer - pos) / refSize) return std::nullopt;
    std::vector<std::uint64_t> out;
    out.reserve(std::size_t(refs));
    for (std::uint64_t r = 0; r < refs; ++r) {
      const std::uint64_t ref = bigEndian(s, std::size_t(pos + r * refSize), refSize);
      if (ref >= objects) return std::nullopt;
      out.push_back(ref);
    }
    return out;
  };

  // Depth-first with an explicit stack; each object's longest chain below it is kept (0 = not
  // yet known), so an object shared by many parents is walked once.
  enum : unsigned char { Unseen, OnPath, Done };
  std::vector<unsigned char> state(std::size_t(objects), Unseen);
  std::vector<std::uint32_t> below(std::size_t(objects), 0);
  struct Frame { std::uint64_t object; std::vector<std::uint64_t> refs; std::size_t next = 0; };
  std::vector<Frame> path;
  const auto enter = [&](std::uint64_t object) -> Status {
    auto refs = children(object);
    if (!refs) return malformed("an object or reference outside the file");
    state[std::size_t(object)] = OnPath;
    path.push_back({object, std::move(*refs)});
    if (path.size() > maxDepth) return tooDeep(where, maxDepth);
    return {};
  };
  if (auto ok = enter(top); !ok) return ok;
  while (!path.empty()) {
    Frame& f = path.back();
    if (f.next < f.refs.size()) {
      const std::uint64_t child = f.refs[f.next++];
      if (state[std::size_t(child)] == OnPath) return malformed("an object contains itself");
      if (state[std::size_t(child)] == Unseen) {
        if (auto ok = enter(child); !ok) return ok;
        continue;
      }
      if (path.size() + below[std::size_t(child)] + 1 > maxDepth) return tooDeep(where, maxDepth);
      below[std::size_t(f.object)] = std::max(below[std::size_t(f.object)], below[std::size_t(child)] + 1);
    } else {
      const std::uint64_t done = f.object;
      state[std::size_t(done)] = Done;
      path.pop_back();
      if (path.size() + below[std::size_t(done)] + 1 > maxDepth) return tooDeep(where, maxDepth);
      if (!path.empty())
        below[std::size_t(path.back().object)] = std::max(below[std::size_t(path.back().object)], below[std::size_t(done)] + 1);
    }
  }
  return {};
}

}  // namespace

Status checkPlistDepth(std::string_view bytes, const std::string& where, std::size_t maxDepth) {
  if (bytes.substr(0, 6) == "bplist") return binaryDepth(bytes, where, maxDepth);
  return xmlDepth(bytes, where, maxDepth);
}

}  // namespace at::inv3
