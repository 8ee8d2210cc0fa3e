// The skull CT (scripts/fetch-scans.sh) with its labels grown now from the seeds kept in
// data/segmentations/skull/ by `anatomy-tutor segment`, as scripts/label-scans.sh does at set-up,
// in a temporary cache folder (XDG_CACHE_HOME) beside a link to the fetched Cranium.inv3. Tests of
// the skull course set XDG_CACHE_HOME to it (SkullCacheScope) so `skull` opens with those labels.
#pragma once

#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "test_support.h"
#include "volume/known_scans.h"

namespace at::test {

// Sets an environment variable for a scope and restores it after.
class ScopedEnvVar {
 public:
  ScopedEnvVar(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnvVar() {
    if (old_) ::setenv(name_, old_->c_str(), 1);
    else ::unsetenv(name_);
  }
  ScopedEnvVar(const ScopedEnvVar&) = delete;
  ScopedEnvVar& operator=(const ScopedEnvVar&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

inline std::filesystem::path skullSeedsFile() { return sourceDir() / "data" / "segmentations" / "skull" / "seeds.json"; }

// The cache folder (grown once per test process), or nullopt after a "SKIPPED: ..." line when the
// scan is not fetched or the app is not built. A failing `segment` run fails the calling test.
inline const std::optional<std::filesystem::path>& grownSkullCache() {
  static TempDir dir("skull-cache");
  static const std::optional<std::filesystem::path> cache = []() -> std::optional<std::filesystem::path> {
    namespace fs = std::filesystem;
    const KnownScan* scan = findKnownScan("skull");
    const auto file = scan ? locateKnownScan(*scan) : std::nullopt;
    if (!file) {
      at::test::skipf("the skull course needs Cranium.inv3 from Debian's invesalius-examples (run scripts/fetch-scans.sh)");
      return std::nullopt;
    }
    if (!requireAppBinary("growing the skull's labels")) return std::nullopt;
    const fs::path folder = dir.path() / "anatomy-tutor" / "scans" / scan->debianPackage;
    fs::create_directories(folder);
    fs::create_symlink(fs::absolute(*file), folder / scan->fileName);
    ScopedEnvVar env("XDG_CACHE_HOME", dir.path().string());
    const auto r = runApp("segment skull --seeds '" + skullSeedsFile().string() + "' --method grow --backend cpu --out '" +
                          (folder / "skull.labels.nii.gz").string() + "' --names '" +
                          (folder / "skull.labels.names.json").string() + "'");
    if (r.exitCode != 0) {
      FAIL_CHECK("growing the skull's labels failed: " << r.err);
      return std::nullopt;
    }
    return dir.path();
  }();
  return cache;
}

// While alive, `skull` (in this process and in the commands it runs) opens with the grown labels.
class SkullCacheScope {
 public:
  explicit SkullCacheScope(const std::filesystem::path& cache) : env_("XDG_CACHE_HOME", cache.string()) {}

 private:
  ScopedEnvVar env_;
};

}  // namespace at::test
