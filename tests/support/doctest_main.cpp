// The test binaries' main: doctest, with the user's data folder replaced by a temporary one for the
// whole run, so that no test (nor the app binaries the tests start, which inherit it) reads or
// writes the database of the person running the tests. Tests that need a database pass --db.
// `--at-backend=postgres` (for CTest, which registers each case with its own arguments) is the same
// as AT_TEST_BACKEND=postgres: the storage tests run on the PostgreSQL server.
#define DOCTEST_CONFIG_IMPLEMENT
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>

#include "test_support.h"

namespace {
// Counts the test cases run, for at::test::exitStatusWithSkips.
struct CaseCounter : doctest::IReporter {
  explicit CaseCounter(const doctest::ContextOptions&) {}
  void report_query(const doctest::QueryData&) override {}
  void test_run_start() override {}
  void test_run_end(const doctest::TestRunStats&) override {}
  void test_case_start(const doctest::TestCaseData&) override { ++at::test::testCasesStarted(); }
  void test_case_reenter(const doctest::TestCaseData&) override {}
  void test_case_end(const doctest::CurrentTestCaseStats&) override {}
  void test_case_exception(const doctest::TestCaseException&) override {}
  void subcase_start(const doctest::SubcaseSignature&) override {}
  void subcase_end() override {}
  void log_assert(const doctest::AssertData&) override {}
  void log_message(const doctest::MessageData&) override {}
  void test_case_skipped(const doctest::TestCaseData&) override {}
};
REGISTER_LISTENER("at_case_counter", 1, CaseCounter);
}  // namespace

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--at-backend=postgres") ::setenv("AT_TEST_BACKEND", "postgres", 1);
  std::string dir = (std::filesystem::temp_directory_path() / "at-xdg-XXXXXX").string();
  const bool made = ::mkdtemp(dir.data()) != nullptr;
  if (made) ::setenv("XDG_DATA_HOME", dir.c_str(), 1);
  doctest::Context context(argc, argv);
  const int status = context.run();
  if (made) {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  return at::test::exitStatusWithSkips(status);
}
