#include "db/class_accounts.h"

#include <functional>
#include <random>

#include "database.h"
#include "server_refusal.h"

namespace at::db {

namespace {

Status requireServer(Database& db, const char* what) {
  if (db.backend() != Backend::Postgres)
    return fail(std::string(what) + " are for a class server (postgresql://…), not the local file " + db.path());
  return {};
}

// Letters and digits a generated password is drawn from (no look-alikes: it is read aloud or typed).
constexpr std::string_view kPasswordAlphabet = "abcdefghijkmnpqrstuvwxyzABCDEFGHJKLMNPQRSTUVWXYZ23456789";

std::string newPassword() {
  std::random_device entropy;  // /dev/urandom on Linux
  std::uniform_int_distribution<std::size_t> pick(0, kPasswordAlphabet.size() - 1);
  std::string out;
  for (int i = 0; i < 24; ++i) out += kPasswordAlphabet[pick(entropy)];
  return out;
}

Status callFunction(Database& server, const std::string& sql, const std::function<void(Statement&)>& bindAll) {
  auto s = server.prepare(sql);
  if (!s) return tl::unexpected(s.error());
  bindAll(*s);
  auto row = s->step();
  if (!row) return tl::unexpected(serverRefusal(row.error()));
  return {};
}

}  // namespace

Result<ServerIdentity> serverIdentity(Database& server) {
  if (auto ok = requireServer(server, "logins"); !ok) return tl::unexpected(ok.error());
  auto s = server.prepare("SELECT session_user::text, at_is_account()");
  if (!s) return tl::unexpected(s.error());
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::Io, "the class server did not say who this connection is");
  return ServerIdentity{s->text(0), s->text(1) == "t" || s->text(1) == "true" || s->text(1) == "1"};
}

Result<std::string> actingName(Database& server, const std::optional<std::string>& claimed) {
  if (server.backend() == Backend::Postgres) {
    auto identity = serverIdentity(server);
    if (!identity) return tl::unexpected(identity.error());
    if (identity->account) {
      if (claimed && !claimed->empty() && *claimed != identity->login)
        return fail(ErrorKind::Conflict, "you are logged in to the class server as " + identity->login +
                                             "; --user " + *claimed + " cannot change who you are there");
      return identity->login;
    }
  }
  if (!claimed || claimed->empty()) return fail("--user NAME is required (who acts)");
  return *claimed;
}

Result<ClassAccount> createClassAccount(Database& server, const std::string& code, const std::string& name,
                                        ClassRole role, const std::optional<std::string>& by) {
  if (auto ok = requireServer(server, "accounts"); !ok) return tl::unexpected(ok.error());
  const std::string password = newPassword();
  std::string outcome;
  auto status = server.writeTransaction([&](Database& d) -> Status {
    auto s = d.prepare("SELECT at_create_account(?1, ?2, ?3, ?4, ?5)");
    if (!s) return tl::unexpected(s.error());
    s->bind(1, code).bind(2, name).bind(3, toString(role)).bind(4, password).bind(5, by.value_or(""));
    auto row = s->step();
    if (!row) return tl::unexpected(serverRefusal(row.error()));
    outcome = *row ? s->text(0) : "";
    return {};
  });
  if (!status) return tl::unexpected(withContext("account '" + name + "' in class " + code, status.error()));
  ClassAccount account{name, role, std::nullopt};
  if (outcome == "created") account.password = password;
  return account;
}

Status withdrawMember(Database& server, const std::string& code, const std::string& member, const std::string& reason,
                      const std::optional<std::string>& by) {
  if (auto ok = requireServer(server, "withdrawals"); !ok) return ok;
  return server.writeTransaction([&](Database& d) -> Status {
    return callFunction(d, "SELECT at_withdraw(?1, ?2, ?3, ?4)",
                        [&](Statement& s) { s.bind(1, code).bind(2, member).bind(3, reason).bind(4, by.value_or("")); });
  });
}

Status correctClassEvent(Database& server, const std::string& eventUuid, bool correct, double score,
                         const std::string& reason, const std::optional<std::string>& by) {
  if (auto ok = requireServer(server, "corrections"); !ok) return ok;
  return server.writeTransaction([&](Database& d) -> Status {
    return callFunction(d, "SELECT at_correct_event(?1, ?2, ?3, ?4, ?5)", [&](Statement& s) {
      s.bind(1, eventUuid).bind(2, std::int64_t(correct ? 1 : 0)).bind(3, score).bind(4, reason).bind(5, by.value_or(""));
    });
  });
}

Result<std::vector<ClassAuditEntry>> classAudit(Database& server, const std::string& code) {
  if (auto ok = requireServer(server, "audits"); !ok) return tl::unexpected(ok.error());
  auto s = server.prepare(
      "SELECT id, recorded_at, actor, login, action, target, old_value, new_value, reason FROM class_audit"
      " WHERE class_code = ?1 ORDER BY id");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, code);
  std::vector<ClassAuditEntry> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    out.push_back({r.int64(0), r.text(1), r.text(2), r.text(3), r.text(4), r.text(5), r.optionalText(6),
                   r.optionalText(7), r.text(8)});
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

}  // namespace at::db
