// A small command-line argument reader for the subcommands: positional arguments and
// `--name value` / `--flag` options. Unknown options are errors naming the option.
#pragma once

#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"

namespace at::cli {

class Args {
 public:
  // `valued`: options that take a value; `flags`: options that take none. "--help" is always a flag.
  static Result<Args> parse(const std::vector<std::string>& argv, const std::set<std::string>& valued,
                            const std::set<std::string>& flags);

  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& name) const { return values_.count(name) > 0 || flags_.count(name) > 0; }
  std::optional<std::string> value(const std::string& name) const;
  std::string valueOr(const std::string& name, const std::string& fallback) const;
  Result<double> number(const std::string& name, double fallback) const;
  Result<int> integer(const std::string& name, int fallback) const;

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
  std::set<std::string> flags_;
};

}  // namespace at::cli
