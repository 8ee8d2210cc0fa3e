// Shared by the libFuzzer harnesses (tests/fuzz/fuzz_*.cpp): a scratch folder for the loaders that
// read files, splitting one input into several files, and the contract every reader must keep on
// any input — return a value or a one-line error naming its source, never crash, hang or leak.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"

namespace at::fuzz {

// Memory limit handed to the image loaders (ImageLoadOptions::maxBytes): well inside libFuzzer's
// default -rss_limit_mb=2048, so an input is refused by the loader's own check, never by the fuzzer.
inline constexpr std::size_t kLoaderMaxBytes = std::size_t(64) << 20;

// Several files from one input: the parts between lines "--8<--" (the seeds write them; mutations
// may break them, which simply yields fewer parts).
inline std::vector<std::string_view> splitParts(const std::uint8_t* data, std::size_t size, std::size_t maxParts) {
  static constexpr std::string_view kSeparator = "\n--8<--\n";
  std::vector<std::string_view> parts;
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  while (parts.size() + 1 < maxParts) {
    const std::size_t at = rest.find(kSeparator);
    if (at == std::string_view::npos) break;
    parts.push_back(rest.substr(0, at));
    rest.remove_prefix(at + kSeparator.size());
  }
  parts.push_back(rest);
  return parts;
}

// One folder per process, emptied before each input and removed at exit. Below $AT_FUZZ_SCRATCH
// when set (a machine whose /dev/shm is too small for many fuzzers at once), else in /dev/shm when
// it exists (no disk writes at thousands of inputs a second), else in the temporary folder.
class Scratch {
 public:
  static Scratch& instance() {
    static Scratch scratch;
    return scratch;
  }
  // An empty folder for this input.
  const std::filesystem::path& fresh() {
    std::error_code ec;
    for (const auto& entry : std::filesystem::directory_iterator(root_, ec)) std::filesystem::remove_all(entry, ec);
    return root_;
  }
  std::filesystem::path write(const std::string& name, std::string_view bytes) {
    const std::filesystem::path path = root_ / name;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
    return path;
  }
  ~Scratch() {
    std::error_code ec;
    std::filesystem::remove_all(root_, ec);
  }

 private:
  Scratch() {
    std::error_code ec;
    const char* chosen = std::getenv("AT_FUZZ_SCRATCH");
    const std::filesystem::path base = chosen && *chosen                              ? std::filesystem::path(chosen)
                                       : std::filesystem::is_directory("/dev/shm", ec) ? std::filesystem::path("/dev/shm")
                                                                                       : std::filesystem::temp_directory_path();
    std::string pattern = (base / "at-fuzz-XXXXXX").string();
    if (!mkdtemp(pattern.data())) {
      std::perror("at-fuzz: cannot create a scratch folder");
      std::abort();
    }
    root_ = pattern;
  }
  std::filesystem::path root_;
};

// The input as the one file `name` of a fresh scratch folder; returns its path.
inline std::string inputAsFile(const std::uint8_t* data, std::size_t size, const std::string& name) {
  auto& scratch = Scratch::instance();
  scratch.fresh();
  return scratch.write(name, std::string_view(reinterpret_cast<const char*>(data), size)).string();
}

// Aborts (a finding) when a reader breaks its error contract: the message must be one non-empty
// line that starts with the file or source it names.
inline void checkError(const Error& error, std::string_view source) {
  const std::string& m = error.message;
  const bool ok = !m.empty() && m.find('\n') == std::string::npos && m.find('\r') == std::string::npos &&
                  (source.empty() || m.compare(0, source.size(), source) == 0);
  if (!ok) {
    std::fprintf(stderr, "at-fuzz: error message breaks the contract (one line, starting with '%.*s'):\n%s\n",
                 int(source.size()), source.data(), m.c_str());
    std::abort();
  }
}

template <class T>
void checkResult(const Result<T>& result, std::string_view source) {
  if (!result) checkError(result.error(), source);
}

// An invariant a successful result must satisfy.
inline void expect(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "at-fuzz: invariant violated: %s\n", what);
    std::abort();
  }
}

}  // namespace at::fuzz
