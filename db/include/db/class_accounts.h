// People on a class server: one PostgreSQL login per person, and the audited changes a
// coordinator makes (roles, withdrawals, corrections).
//
// A person's login ("an account", made by createClassAccount) is who they are on the server: the
// server's functions act as that login and refuse any other name, whatever `--user` says. The
// administrator's connection (the database's owner or a superuser) is not an account; it may name
// the member it acts for, as it owns the tables anyway. Every role change, withdrawal and
// correction is written by the server into its append-only audit (who, which login, when, old and
// new value, reason). On a SQLite file (one person's laptop) there are no accounts.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "db/class_server.h"

namespace at::db {

struct ServerIdentity {
  std::string login;     // the PostgreSQL session user
  bool account = false;  // a person's login made by `class account`
};
// Who this connection is on its server; Invalid on a SQLite file.
Result<ServerIdentity> serverIdentity(Database& server);

// The name acting on `server`: for an account its login (Conflict when `claimed` names anyone
// else: a login cannot act as another person), else `claimed` (Invalid when none is given).
Result<std::string> actingName(Database& server, const std::optional<std::string>& claimed);

struct ClassAccount {
  std::string login;
  ClassRole role = ClassRole::Student;
  std::optional<std::string> password;  // only when the login was made now: shown once, never stored
};
// Makes `name` a login on the server (unless it has one: its password is left alone) and a
// member of the class with `role`. `by`: the coordinator acting (ignored for an account, which acts
// as itself); the administrator may leave it empty. Login names: 2 to 48 of a-z, 0-9 and _.
Result<ClassAccount> createClassAccount(Database& server, const std::string& code, const std::string& name,
                                        ClassRole role, const std::optional<std::string>& by);

// A member withdraws (consent withdrawn) or a coordinator excludes them, with the reason.
Status withdrawMember(Database& server, const std::string& code, const std::string& member, const std::string& reason,
                      const std::optional<std::string>& by);

// A coordinator corrects one stored answer's grade, with the reason.
Status correctClassEvent(Database& server, const std::string& eventUuid, bool correct, double score,
                         const std::string& reason, const std::optional<std::string>& by);

struct ClassAuditEntry {
  std::int64_t id = 0;
  std::string recordedAt;  // ISO-8601 UTC
  std::string actor, login, action, target;
  std::optional<std::string> oldValue, newValue;
  std::string reason;
};
// The class's audit, oldest first (a login reads it only as a coordinator of the class).
Result<std::vector<ClassAuditEntry>> classAudit(Database& server, const std::string& code);

}  // namespace at::db
