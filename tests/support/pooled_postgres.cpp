#include "pooled_postgres.h"

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "test_databases.h"
#include "test_support.h"

namespace at::test {

namespace fs = std::filesystem;

namespace {

// Runs `command` in a shell; its stdout (and stderr, folded in) without the last newline.
std::string run(const std::string& command, int& status) {
  std::string out;
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) {
    status = -1;
    return out;
  }
  char buf[512];
  while (std::fgets(buf, sizeof buf, pipe)) out += buf;
  const int raw = ::pclose(pipe);
  status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

std::string script(const char* name) { return "'" + (sourceDir() / "scripts" / name).string() + "'"; }

std::string tempFolder(const char* prefix) {
  std::string dir = (fs::temp_directory_path() / (std::string(prefix) + "XXXXXX")).string();
  return ::mkdtemp(dir.data()) ? dir : std::string();
}

std::string withDatabase(const std::string& url, const std::string& database) {
  return url.substr(0, url.rfind('/') + 1) + database;
}

}  // namespace

PooledPostgres::PooledPostgres(int serverConnections, int poolSize) {
  clusterDir_ = tempFolder("at-pg-pooled-");
  bouncerDir_ = tempFolder("at-pgbouncer-");
  if (clusterDir_.empty() || bouncerDir_.empty()) {
    whyNot_ = "cannot make temporary folders";
    return;
  }
  clusterWatchdog_ = ServiceWatchdog((sourceDir() / "scripts" / "pg-cluster.sh").string(), clusterDir_);
  bouncerWatchdog_ = ServiceWatchdog((sourceDir() / "scripts" / "pgbouncer.sh").string(), bouncerDir_);
  int status = 0;
  serverUrl_ = run("AT_PG_FAST=1 AT_PG_MAX_CONNECTIONS=" + std::to_string(serverConnections) + " " +
                       script("pg-cluster.sh") + " start '" + clusterDir_ + "'",
                   status);
  if (status != 0) {
    whyNot_ = serverUrl_;
    return;
  }
  clusterStarted_ = true;
  pooledUrl_ = run("AT_PGB_POOL_SIZE=" + std::to_string(poolSize) + " " + script("pgbouncer.sh") + " start '" +
                       bouncerDir_ + "' '" + serverUrl_ + "'",
                   status);
  if (status != 0) {
    whyNot_ = pooledUrl_;
    return;
  }
  bouncerStarted_ = true;
}

PooledPostgres::~PooledPostgres() {
  int status = 0;
  if (bouncerStarted_) run(script("pgbouncer.sh") + " stop '" + bouncerDir_ + "'", status);
  if (clusterStarted_) run(script("pg-cluster.sh") + " stop '" + clusterDir_ + "'", status);
  std::error_code ec;
  if (!bouncerDir_.empty()) fs::remove_all(bouncerDir_, ec);
  if (!clusterDir_.empty()) fs::remove_all(clusterDir_, ec);
}

std::optional<PooledPostgres::Urls> PooledPostgres::freshDatabase() {
  if (!ok()) return std::nullopt;
  const std::string name = "pooled" + std::to_string(::getpid()) + "_" + std::to_string(databases_++);
  if (auto e = execOnServer(serverUrl_, "CREATE DATABASE " + name); !e.empty()) {
    whyNot_ = "cannot create a database: " + e;
    return std::nullopt;
  }
  return Urls{withDatabase(serverUrl_, name), withDatabase(pooledUrl_, name)};
}

std::optional<PooledPostgres::Urls> pooledDatabase(PooledPostgres& server, const char* what) {
  auto urls = server.freshDatabase();
  if (!urls) at::test::skipf("%s needs PostgreSQL and PgBouncer: %s", what, server.whyNot().c_str());
  return urls;
}

}  // namespace at::test
