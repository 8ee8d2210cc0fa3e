// The one command-line reader of anatomy-tutor, for every command and the desktop alike:
// positional arguments, `--name value` / `--name=value` options and `--flag`s. Unknown options
// are errors naming the option.
//
// Global options — `--db PATH`, `--user NAME`, `--size WxH` — are accepted by every command and
// may stand before the command's name as well as after it (`anatomy-tutor --db X lessons`); they
// are checked here once: `--db` must name a database file that can be used (not a folder, not an
// option, in a folder that exists) or a PostgreSQL server (postgresql://…), `--user` must not be empty and `--size`
// must be WxH with 1..8192 pixels per side.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"

namespace at::cli {

// "db", "user", "size": the options every command takes.
const std::set<std::string>& globalOptions();

struct PixelSize {
  int width = 0, height = 0;
};
// "WxH" with 1..8192 pixels per side.
Result<PixelSize> parsePixelSize(const std::string& text);

// The command line without the program's name, split into the command and its arguments. Global
// options before the command go to it (after its own arguments). No word but global options
// (or nothing): the command is empty — the program's default. A first word that is another
// option (`anatomy-tutor --ui-script F.json`) belongs to the desktop: the command is "desktop".
// "--help", "-h", "help" and "--version" first are returned as the command.
struct CommandLine {
  std::string command;
  std::vector<std::string> args;
};
Result<CommandLine> splitCommandLine(const std::vector<std::string>& argv);

class Args {
 public:
  // `valued`: options that take a value; `flags`: options that take none. "--help" is always a
  // flag; the global options are always valued (and validated).
  static Result<Args> parse(const std::vector<std::string>& argv, const std::set<std::string>& valued,
                            const std::set<std::string>& flags);

  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& name) const { return values_.count(name) > 0 || flags_.count(name) > 0; }
  std::optional<std::string> value(const std::string& name) const;
  std::string valueOr(const std::string& name, const std::string& fallback) const;
  Result<double> number(const std::string& name, double fallback) const;
  Result<int> integer(const std::string& name, int fallback) const;

  // The global options, checked by parse().
  std::optional<std::string> db() const { return value("db"); }
  std::optional<std::string> user() const { return value("user"); }
  std::optional<PixelSize> size() const { return size_; }

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
  std::optional<PixelSize> size_;
};

}  // namespace at::cli
