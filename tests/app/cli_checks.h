// Checks on commands run as a user would (test::runApp).
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <string>

#include "test_support.h"

namespace at::test {

// A failing command says what is wrong on exactly one line of stderr.
inline void checkOneLineError(const CommandResult& r, const std::string& mustMention) {
  CHECK(r.exitCode != 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find(mustMention) != std::string::npos);
  CHECK(r.err.rfind("anatomy-tutor: ", 0) == 0);
}

}  // namespace at::test
