#include "printable_output.h"

#include <cstdarg>
#include <string>

#include "core/printable_text.h"

namespace at::app {

namespace {

int printSafely(std::FILE* stream, const char* format, std::va_list args) {
  std::va_list copy;
  va_copy(copy, args);
  const int length = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  if (length < 0) return -1;
  std::string text(std::size_t(length) + 1, '\0');
  std::vsnprintf(text.data(), text.size(), format, args);
  text.resize(std::size_t(length));
  const std::string safe = printableLines(text);
  return std::fwrite(safe.data(), 1, safe.size(), stream) == safe.size() ? int(safe.size()) : -1;
}

}  // namespace

int terminalPrintf(const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  const int written = printSafely(stdout, format, args);
  va_end(args);
  return written;
}

int terminalFprintf(std::FILE* stream, const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  const int written = printSafely(stream, format, args);
  va_end(args);
  return written;
}

std::string rowCell(std::string_view outside) { return printableText(outside, 1000); }

}  // namespace at::app
