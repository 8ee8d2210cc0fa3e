// Several store calls as one write transaction.
#pragma once

#include <functional>

#include "core/error.h"
#include "db/connection.h"

namespace at::db {

// Runs `body` — calls to the stores — as one write transaction: each store's own transaction joins
// it, so either everything `body` wrote is committed or, when it fails (or the process dies before
// it returns), none of it is. Retried whole on contention like every write (body may run again).
Status writeAllOrNothing(Database& database, const std::function<Status()>& body);

}  // namespace at::db
