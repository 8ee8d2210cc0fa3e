// Errors as values across module boundaries (STYLE.md): expected failures — a bad file, a missing
// structure, a full disk — travel as `Error` inside `Result<T>`. An Error carries a kind, so that a
// caller that must tell failures apart (a name already taken, a cancelled import) branches on the
// kind and never on the message text, and a message a user can act on ("series has 2 different
// slice spacings: 2.0 and 2.5 mm"). Programmer mistakes assert instead.
#pragma once

#include <string>
#include <utility>

#include <tl/expected.hpp>

namespace at {

enum class ErrorKind {
  Invalid,      // the input is wrong: a malformed file, an argument out of range (the default)
  NotFound,     // a named thing does not exist: a file, dataset, structure, user, course
  Conflict,     // it clashes with what is stored: a name or id already taken, a broken reference
  Io,           // the system or a library failed to read or write (disk full, permission, SQL engine)
  Unavailable,  // a capability this machine or build lacks: no CUDA device, no display, no GL 4.3
  Cancelled,    // the caller asked to stop; nothing more is wrong
};

// "invalid", "not found", "conflict", "I/O", "unavailable", "cancelled".
const char* toString(ErrorKind kind);

struct Error {
  ErrorKind kind = ErrorKind::Invalid;
  std::string message;  // one line, names the file or field and the problem
};

template <class T>
using Result = tl::expected<T, Error>;

// A Result that carries no value: success or an Error.
using Status = tl::expected<void, Error>;

// `return fail("…");` from any function returning Result<T> or Status: an Invalid error.
inline tl::unexpected<Error> fail(std::string message) {
  return tl::unexpected<Error>(Error{ErrorKind::Invalid, std::move(message)});
}

// `return fail(ErrorKind::NotFound, "…");` where callers may branch on what went wrong.
inline tl::unexpected<Error> fail(ErrorKind kind, std::string message) {
  return tl::unexpected<Error>(Error{kind, std::move(message)});
}

// Prefixes an error with context ("cochlea.nrrd: " + "unknown encoding 'bz3'"); the kind stays.
inline Error withContext(const std::string& context, Error error) {
  error.message = context + ": " + error.message;
  return error;
}

}  // namespace at
