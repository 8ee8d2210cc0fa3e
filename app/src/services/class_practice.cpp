#include "class_practice.h"

#include "db/class_server.h"

namespace at::app {

namespace {
// What counts on the server, in both notes.
constexpr const char* kWhatCounts = "there a locate answer counts only as the pixel x y picked on the question's picture";
}  // namespace

bool answersGoToClassServer(db::Database& local, const std::string& userName) {
  if (db::backendOf(local) != db::Backend::Sqlite) return false;  // a server's own tables: no outbox
  auto joined = db::membershipOf(local, userName);
  return joined && joined->has_value();
}

bool classServerGrades(const quiz::Pick& pick) { return pick.pixel.has_value() && !pick.view.empty(); }

std::string practicePickNote() { return std::string("your class server keeps this pick as practice: ") + kWhatCounts; }

std::string practiceClickAheadNote() {
  return std::string("your class server will keep a click in the 3-D view as practice: ") + kWhatCounts +
         ", which `anatomy-tutor play` shows";
}

}  // namespace at::app
