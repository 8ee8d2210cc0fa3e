// Text from outside (a field value quoted in an error, a structure name from a label file, a study
// title) made safe for a one-line message, a terminal or a Markdown/CSV cell's neighbourhood: no
// line breaks, no terminal escape sequences, no bidirectional overrides, valid UTF-8.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace at {

// Control characters (C0, DEL, C1), line and paragraph separators and bidirectional controls become
// escapes (\n, \t, \x1b, \u202e); bytes that are not valid UTF-8 become \xNN; printable UTF-8
// (accents, CJK) is kept. Longer text is cut after `maxChars` characters with "…".
std::string printableText(std::string_view text, std::size_t maxChars = 120);

// Text of several lines for a terminal or a UI text block (a lesson's text, a course listing, a
// command's whole output): as printableText, but line breaks (\n) and tabs are kept, and nothing is
// cut. What it returns can reach a terminal raw: it holds no escape sequence, no cursor control, no
// bidirectional override.
std::string printableLines(std::string_view text);

// Outside text for the desktop's widgets (Dear ImGui): printableLines, and "##" shown as "# #",
// because ImGui takes what follows "##" in a widget's label as its hidden id (a title "A##B" would
// show as "A"). Draw with a "%s" format (or TextUnformatted), never as the format itself.
std::string printableUiText(std::string_view text);

}  // namespace at

#include "core/error.h"

namespace at {

// An error whose message quotes outside text, made one printable line (printableText, long limit):
// the last step of every reader of outside data before its error leaves it.
inline Error printableError(Error error) {
  error.message = printableText(error.message, 2000);
  return error;
}

template <class T>
tl::expected<T, Error> withPrintableError(tl::expected<T, Error> result) {
  if (!result) return tl::unexpected(printableError(std::move(result.error())));
  return result;
}

}  // namespace at
