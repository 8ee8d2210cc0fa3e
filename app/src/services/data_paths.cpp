#include "data_paths.h"

#include <cstdlib>

namespace at::app {

namespace fs = std::filesystem;

namespace {

// The running executable's folder, from the kernel (argv[0] may be a bare name found on PATH).
fs::path executableFolder() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : exe.parent_path();
}

}  // namespace

std::vector<fs::path> dataSearchPath() {
  std::vector<fs::path> places;
  if (const char* dir = std::getenv("AT_DATA_DIR"); dir && *dir) places.emplace_back(dir);
  if (const fs::path exe = executableFolder(); !exe.empty())
    places.push_back((exe.parent_path() / "share" / "anatomy-tutor").lexically_normal());
  places.emplace_back(AT_INSTALL_DATA_DIR);
  return places;
}

fs::path dataSubdirectory(const std::string& name) {
  const std::vector<fs::path> places = dataSearchPath();
  for (const fs::path& place : places) {
    std::error_code ec;
    if (fs::is_directory(place / name, ec)) return place / name;
  }
  return places.front() / name;
}

}  // namespace at::app
