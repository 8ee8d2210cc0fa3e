// One lab machine in a class-server test: its own data folder (XDG_DATA_HOME, where a machine keeps
// its copies of a server's scans) while in scope.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

namespace at::test {

class OnMachine {
 public:
  explicit OnMachine(const std::filesystem::path& dataHome) {
    if (const char* old = std::getenv("XDG_DATA_HOME")) previous_ = old;
    ::setenv("XDG_DATA_HOME", dataHome.c_str(), 1);
  }
  ~OnMachine() {
    if (previous_) ::setenv("XDG_DATA_HOME", previous_->c_str(), 1);
    else ::unsetenv("XDG_DATA_HOME");
  }
  OnMachine(const OnMachine&) = delete;
  OnMachine& operator=(const OnMachine&) = delete;

 private:
  std::optional<std::string> previous_;
};

}  // namespace at::test
