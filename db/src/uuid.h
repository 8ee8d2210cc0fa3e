// Random (version 4) UUIDs for the events a learner's machine sends to a class server: minted
// where an event happens, so that two machines never mint the same one and a server can tell an
// event it already has by its UUID alone.
#pragma once

#include <string>

namespace at::db {

// "xxxxxxxx-xxxx-4xxx-Nxxx-xxxxxxxxxxxx" in lower-case hex (N is 8, 9, a or b): 122 random bits
// from a generator seeded per thread by std::random_device.
std::string newUuid();

// True for that form (any version).
bool isUuid(const std::string& text);

}  // namespace at::db
