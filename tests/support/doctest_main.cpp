// The test binaries' main: doctest, with the user's data folder replaced by a temporary one for the
// whole run, so that no test (nor the app binaries the tests start, which inherit it) reads or
// writes the database of the person running the tests. Tests that need a database pass --db.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

int main(int argc, char** argv) {
  std::string dir = (std::filesystem::temp_directory_path() / "at-xdg-XXXXXX").string();
  const bool made = ::mkdtemp(dir.data()) != nullptr;
  if (made) ::setenv("XDG_DATA_HOME", dir.c_str(), 1);
  doctest::Context context(argc, argv);
  const int status = context.run();
  if (made) {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  return status;
}
