// The desktop's layers, read off the sources' #include lines: DesktopModel owns the feature
// controllers, so a controller (any file of a feature folder that is neither its script actions
// nor under its ui/) includes neither desktop_model.h nor the interpreter's or the window's
// headers, which include the model. What a feature puts on the view is the model's own code in
// desktop/desktop_model_<feature>.cpp.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "test_support.h"

namespace fs = std::filesystem;

namespace {

// The quoted #include targets of one source file, in order.
std::vector<std::string> quotedIncludes(const fs::path& file) {
  std::vector<std::string> found;
  std::ifstream in(file);
  const std::string directive = "#include \"";
  for (std::string line; std::getline(in, line);)
    if (line.rfind(directive, 0) == 0) {
      const std::size_t end = line.find('"', directive.size());
      if (end != std::string::npos) found.push_back(line.substr(directive.size(), end - directive.size()));
    }
  return found;
}

bool isSource(const fs::path& p) { return p.extension() == ".cpp" || p.extension() == ".h"; }

}  // namespace

TEST_CASE("no desktop feature controller includes the model, the script interpreter or the window shell") {
  const fs::path desktop = at::test::sourceDir() / "app" / "src" / "desktop";
  REQUIRE(fs::is_directory(desktop));
  // script/ and ui/ sit above the model (they drive it); every other folder is a feature.
  const std::set<std::string> aboveTheModel = {"script", "ui"};
  int controllers = 0;
  for (const fs::directory_entry& feature : fs::directory_iterator(desktop)) {
    if (!feature.is_directory() || aboveTheModel.count(feature.path().filename().string())) continue;
    for (const fs::directory_entry& e : fs::recursive_directory_iterator(feature.path())) {
      const fs::path rel = fs::relative(e.path(), feature.path());
      if (!e.is_regular_file() || !isSource(e.path())) continue;
      if (*rel.begin() == "ui" || e.path().filename().string().rfind("script_actions_", 0) == 0) continue;
      ++controllers;
      for (const std::string& include : quotedIncludes(e.path())) {
        INFO(fs::relative(e.path(), desktop).string() << " includes \"" << include << "\"");
        CHECK(include.rfind("desktop_model", 0) != 0);
        CHECK(include.rfind("script/", 0) != 0);
        CHECK(include.rfind("ui/", 0) != 0);
      }
    }
  }
  CHECK(controllers >= 8);  // the scan found the feature folders' logic files
}
