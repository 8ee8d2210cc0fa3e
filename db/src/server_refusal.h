// A class server function's refusal as the person should read it.
#pragma once

#include "core/error.h"

namespace at::db {

// The error of a failed call to one of the class server's functions (class_security_sql.cpp)
// without the driver's wrapping ("SQL error: ERROR:  …  in: SELECT …"): just the server's reason,
// with the error's kind kept.
Error serverRefusal(const Error& error);

}  // namespace at::db
