#include "core/safe_name.h"

#include "core/printable_text.h"

namespace at {

namespace fs = std::filesystem;

namespace {

bool asciiLetterOrDigit(unsigned char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9'); }

// Why `name` breaks the rule, or "" when it keeps it.
std::string whyUnsafe(std::string_view name) {
  if (name.empty()) return "empty";
  if (name.size() > kMaxSafeNameBytes) return "longer than " + std::to_string(kMaxSafeNameBytes) + " characters";
  for (unsigned char c : name) {
    if (c == '/' || c == '\\') return "a path, not a name (it holds a folder separator)";
    if (c >= 0x80) return "not plain ASCII (Unicode names are refused: look-alike letters could name another folder)";
    if (!asciiLetterOrDigit(c) && c != '_' && c != '-' && c != '.') return "holds a character other than letters, digits, '_', '-', '.'";
  }
  if (name == "." || name == "..") return "a folder reference, not a name";
  const unsigned char first = static_cast<unsigned char>(name.front());
  if (first == '.') return "starts with '.' (a hidden name)";
  if (first == '-') return "starts with '-' (it would read as an option)";
  if (name.back() == '.') return "ends with '.'";
  return "";
}

// `p` with symbolic links resolved as far as it exists (the rest appended as written).
fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
  return ec ? fs::absolute(p).lexically_normal() : r;
}

}  // namespace

bool isSafeName(std::string_view name) { return whyUnsafe(name).empty(); }

Status checkSafeName(std::string_view field, std::string_view name) {
  const std::string why = whyUnsafe(name);
  if (why.empty()) return {};
  return fail(std::string(field) + " '" + printableText(name, 80) + "' is refused: " + why +
              " (a name is 1 to " + std::to_string(kMaxSafeNameBytes) +
              " ASCII letters, digits, '_', '-' or '.', starting with a letter, digit or '_')");
}

bool isInside(const fs::path& base, const fs::path& path) {
  const fs::path b = resolved(base), p = resolved(path);
  auto bi = b.begin(), pi = p.begin();
  for (; bi != b.end(); ++bi, ++pi) {
    if (bi->empty()) continue;  // a trailing separator
    if (pi == p.end() || *bi != *pi) return false;
  }
  for (; pi != p.end(); ++pi)
    if (!pi->empty()) return true;
  return false;
}

Result<fs::path> confinedPath(const fs::path& base, std::initializer_list<std::string_view> components, std::string_view field) {
  std::error_code ec;
  if (!fs::is_directory(base, ec)) return fail(ErrorKind::NotFound, std::string(field) + ": " + base.string() + ": no such folder");
  if (components.size() == 0) return fail(std::string(field) + ": no name under " + base.string());
  fs::path out = base;
  for (std::string_view c : components) {
    if (auto ok = checkSafeName(field, c); !ok) return tl::unexpected(ok.error());
    out /= fs::path(std::string(c));
  }
  if (!isInside(base, out))
    return fail(std::string(field) + ": " + printableText(out.string(), 200) + " leads outside " + base.string() +
                " (through a symbolic link): refused");
  return out;
}

}  // namespace at
