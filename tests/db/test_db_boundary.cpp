// db/ is the only module that runs SQL: its public headers (db/include/db) are the connection,
// stores and repositories, with no statement, transaction or engine handle; no product code
// outside db/ includes its private SQL wrapper or an engine's header. Read from the checkout.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "test_support.h"

namespace fs = std::filesystem;

namespace {

std::vector<fs::path> sourcesUnder(const fs::path& dir) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".h" || ext == ".cpp" || ext == ".cu" || ext == ".cuh"))
      files.push_back(entry.path());
  }
  return files;
}

}  // namespace

TEST_CASE("db's public headers hold no SQL wrapper: no statement, transaction or engine handle") {
  const auto headers = sourcesUnder(at::test::sourceDir() / "db" / "include");
  REQUIRE(headers.size() >= 8);  // connection.h, the stores and the repositories
  for (const fs::path& header : headers) {
    const std::string text = at::test::readFile(header);
    INFO(header.string());
    for (const char* word : {"class Statement", "class Transaction", "prepare(", "exec(", "writeTransaction",
                             "sqlite3", "PGconn", "libpq-fe.h"})
      CHECK_MESSAGE(text.find(word) == std::string::npos, std::string(word));
  }
}

TEST_CASE("no product code outside db/ includes db's SQL wrapper or an engine's header") {
  std::size_t read = 0;
  for (const char* module : {"app", "bench", "core", "cuda", "lessons", "quiz", "render", "volume", "wdt"}) {
    for (const fs::path& file : sourcesUnder(at::test::sourceDir() / module)) {
      ++read;
      const std::string text = at::test::readFile(file);
      INFO(file.string());
      for (const char* include : {"#include \"database.h\"", "#include \"schema.h\"", "#include \"backend.h\"",
                                  "#include \"db/database.h\"", "#include <sqlite3.h>", "#include <libpq-fe.h>"})
        CHECK_MESSAGE(text.find(include) == std::string::npos, std::string(include));
    }
  }
  CHECK(read > 100);
}
