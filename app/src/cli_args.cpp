#include "cli_args.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

namespace at::cli {

Result<Args> Args::parse(const std::vector<std::string>& argv, const std::set<std::string>& valued,
                         const std::set<std::string>& flags) {
  Args args;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a.size() > 2 && a.compare(0, 2, "--") == 0) {
      std::string name = a.substr(2), inlineValue;
      bool hasInline = false;
      if (auto eq = name.find('='); eq != std::string::npos) {
        inlineValue = name.substr(eq + 1);
        name = name.substr(0, eq);
        hasInline = true;
      }
      if (name == "help" || flags.count(name)) {
        if (hasInline) return fail("option --" + name + " takes no value");
        args.flags_.insert(name);
      } else if (valued.count(name)) {
        if (hasInline) {
          args.values_[name] = inlineValue;
        } else {
          if (i + 1 >= argv.size()) return fail("option --" + name + " needs a value");
          args.values_[name] = argv[++i];
        }
      } else {
        return fail("unknown option --" + name + " (see --help)");
      }
    } else {
      args.positional_.push_back(a);
    }
  }
  return args;
}

std::optional<std::string> Args::value(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Args::valueOr(const std::string& name, const std::string& fallback) const {
  return value(name).value_or(fallback);
}

Result<double> Args::number(const std::string& name, double fallback) const {
  auto v = value(name);
  if (!v) return fallback;
  errno = 0;
  char* end = nullptr;
  const double d = std::strtod(v->c_str(), &end);
  if (v->empty() || *end != '\0' || errno != 0 || !std::isfinite(d))
    return fail("option --" + name + ": '" + *v + "' is not a number");
  return d;
}

Result<int> Args::integer(const std::string& name, int fallback) const {
  auto v = value(name);
  if (!v) return fallback;
  errno = 0;
  char* end = nullptr;
  const long n = std::strtol(v->c_str(), &end, 10);
  if (v->empty() || *end != '\0' || errno != 0 || n < -2147483647L || n > 2147483647L)
    return fail("option --" + name + ": '" + *v + "' is not an integer");
  return int(n);
}

}  // namespace at::cli
