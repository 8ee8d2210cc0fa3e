// What a command prints to the terminal, when any part of it may come from outside (a course
// package's titles and texts, structure names from a label file, user names): formatted as printf
// does, then made safe by core's printableLines — control characters, escape sequences and
// bidirectional overrides are shown as escapes (\x1b, \u202e), never sent raw. Line breaks and
// valid UTF-8 stay as they are.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace at::app {

// printf to stdout through printableLines. Returns the bytes written, or -1.
int terminalPrintf(const char* format, ...) __attribute__((format(printf, 1, 2)));

// The same to `stream` (stderr for warnings that quote outside text).
int terminalFprintf(std::FILE* stream, const char* format, ...) __attribute__((format(printf, 2, 3)));

// Outside text that fills one cell of a listing's row (a course or lesson title, a study title, a
// user's name): one line, with line breaks shown as \n, so that no title can start a row of its
// own; cut after 1000 characters with "…". Pass the result through terminalPrintf as usual.
std::string rowCell(std::string_view outside);

}  // namespace at::app
