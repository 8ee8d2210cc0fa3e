// What a command prints to the terminal, when any part of it may come from outside (a course
// package's titles and texts, structure names from a label file, user names): formatted as printf
// does, then made safe by core's printableLines — control characters, escape sequences and
// bidirectional overrides are shown as escapes (\x1b, \u202e), never sent raw. Line breaks and
// valid UTF-8 stay as they are.
#pragma once

#include <cstdio>

namespace at::app {

// printf to stdout through printableLines. Returns the bytes written, or -1.
int terminalPrintf(const char* format, ...) __attribute__((format(printf, 1, 2)));

// The same to `stream` (stderr for warnings that quote outside text).
int terminalFprintf(std::FILE* stream, const char* format, ...) __attribute__((format(printf, 2, 3)));

}  // namespace at::app
