#include "server_refusal.h"

#include <string>

namespace at::db {

Error serverRefusal(const Error& error) {
  std::string message = error.message;
  for (const std::string prefix : {"SQL error: ", "ERROR:  ", "ERROR: "})
    if (message.rfind(prefix, 0) == 0) message.erase(0, prefix.size());
  if (auto in = message.find(" in: SELECT at_"); in != std::string::npos) message.erase(in);
  Error out = error;
  out.message = message;
  return out;
}

}  // namespace at::db
