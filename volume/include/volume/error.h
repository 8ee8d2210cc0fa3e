// Errors as values across module boundaries (STYLE.md): expected failures — a bad file, a missing
// structure, a full disk — travel as `Error` inside `Result<T>`, with a message a user can act on
// ("series has 2 different slice spacings: 2.0 and 2.5 mm"). Programmer mistakes assert instead.
#pragma once

#include <string>
#include <utility>

#include <tl/expected.hpp>

namespace at {

struct Error {
  std::string message;  // one line, names the file or field and the problem
};

template <class T>
using Result = tl::expected<T, Error>;

// A Result that carries no value: success or an Error.
using Status = tl::expected<void, Error>;

// `return fail("…");` from any function returning Result<T> or Status.
inline tl::unexpected<Error> fail(std::string message) {
  return tl::unexpected<Error>(Error{std::move(message)});
}

// Prefixes an error with context ("cochlea.nrrd: " + "unknown encoding 'bz3'").
inline Error withContext(const std::string& context, Error error) {
  error.message = context + ": " + error.message;
  return error;
}

}  // namespace at
