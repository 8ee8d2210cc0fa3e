#include "test_support.h"

#include <atomic>
#include <chrono>
#include <cstdarg>
#include <map>
#include <mutex>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

#include "volume/phantom.h"

namespace at::test {

namespace fs = std::filesystem;

namespace {
std::atomic<bool> skipped{false};
}  // namespace

void skipf(const char* format, ...) {
  std::va_list args;
  va_start(args, format);
  std::fputs("SKIPPED: ", stdout);
  std::vfprintf(stdout, format, args);
  std::fputc('\n', stdout);
  std::fflush(stdout);
  va_end(args);
  skipped = true;
}

std::atomic<int>& testCasesStarted() {
  static std::atomic<int> count{0};
  return count;
}

std::string runCommand(const std::string& command, int& status) {
  std::string out;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) {
    status = -1;
    return out;
  }
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  const int raw = ::pclose(pipe);
  status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return out;
}

int exitStatusWithSkips(int status) {
  return status == 0 && skipped && testCasesStarted() == 1 ? kSkippedExitCode : status;
}

const Dataset& phantomOfSize(int size) {
  static std::mutex mutex;
  static std::map<int, Dataset> cache;
  std::lock_guard lock(mutex);
  auto it = cache.find(size);
  if (it == cache.end()) {
    PhantomOptions options;
    options.size = size;
    it = cache.emplace(size, makePhantom(options)).first;
  }
  return it->second;
}

fs::path sharedDataDir() {
  if (const char* env = std::getenv("AT_SHARED_DATA")) {
    if (fs::is_directory(env)) return env;
  }
  const fs::path configured = AT_SHARED_DATA_DIR;
  if (fs::is_directory(configured)) return fs::canonical(configured);
  return {};
}

fs::path sharedData(const std::string& relative) {
  const fs::path dir = sharedDataDir();
  return dir.empty() ? fs::path{} : dir / relative;
}

bool requireSharedData(const char* what) {
  if (!sharedDataDir().empty()) return true;
  skipf("%s needs ../shared/data, which is absent", what);
  return false;
}

fs::path sourceDir() { return AT_SOURCE_DIR; }

TempDir::TempDir(const std::string& prefix) {
  std::string tmpl = (fs::temp_directory_path() / (prefix + "-XXXXXX")).string();
  char* made = mkdtemp(tmpl.data());
  path_ = made ? fs::path(made) : fs::temp_directory_path() / prefix;
}

TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

std::uint64_t freshSeed(const char* testName) {
  std::uint64_t seed;
  if (const char* env = std::getenv("AT_TEST_SEED")) {
    seed = std::strtoull(env, nullptr, 10);
  } else {
    seed = std::uint64_t(std::chrono::steady_clock::now().time_since_epoch().count()) ^ std::random_device{}();
  }
  std::printf("%s: seed %llu (replay with AT_TEST_SEED=%llu)\n", testName, (unsigned long long)seed,
              (unsigned long long)seed);
  return seed;
}

fs::path appBinary() {
  if (const char* env = std::getenv("AT_APP")) {
    if (fs::exists(env)) return env;
  }
  return fs::path(AT_BINARY_DIR) / "app" / "anatomy-tutor";
}

bool requireAppBinary(const char* what) {
  if (fs::exists(appBinary())) return true;
  skipf("%s needs the anatomy-tutor binary, not built in this tree", what);
  return false;
}

std::string readFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CommandResult runApp(const std::string& args, const std::string& stdinText) {
  TempDir dir("at-run");
  const fs::path in = dir / "stdin", out = dir / "stdout", err = dir / "stderr";
  {
    std::ofstream f(in, std::ios::binary);
    f << stdinText;
  }
  const std::string cmd = "'" + appBinary().string() + "' " + args + " <'" + in.string() + "' >'" +
                          out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  CommandResult r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = readFile(out);
  r.err = readFile(err);
  return r;
}

}  // namespace at::test
