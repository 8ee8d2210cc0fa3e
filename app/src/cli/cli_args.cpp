#include "cli_args.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/strings.h"

#include "db/connection.h"

namespace at::cli {

namespace fs = std::filesystem;

namespace {

// `--db VALUE`: a SQLite file, new or existing, or a PostgreSQL server's database
// (postgresql://…). Refused before anything is created.
Status checkDatabasePath(const std::string& value) {
  if (value.empty()) return fail("option --db needs a database file");
  if (value[0] == '-') return fail("option --db: '" + value + "' is an option, not a database file");
  if (db::isPostgresUrl(value)) return {};
  if (value.find("://") != std::string::npos)
    return fail("option --db: '" + value +
                "' is not a database this program can use: give a SQLite file path or a postgresql:// address");
  std::error_code ec;
  if (fs::is_directory(value, ec))
    return fail("option --db: '" + value + "' is a folder; give a database file in it (e.g. " +
                (fs::path(value) / "anatomy-tutor.db").string() + ")");
  const fs::path parent = fs::path(value).parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec))
    return fail(ErrorKind::NotFound, "option --db: folder '" + parent.string() + "' does not exist (create it first)");
  return {};
}

bool isFlagWord(const std::string& word) { return word.size() > 2 && str::startsWith(word, "--"); }

// The option's name in "--name" or "--name=value".
std::string optionName(const std::string& word) { return word.substr(2, word.find('=') - 2); }

}  // namespace

const std::set<std::string>& globalOptions() {
  static const std::set<std::string> names = {"db", "user", "size"};
  return names;
}

Result<PixelSize> parsePixelSize(const std::string& text) {
  PixelSize s;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &s.width, &x, &s.height, &extra) != 3 || (x != 'x' && x != 'X') ||
      s.width < 1 || s.height < 1 || s.width > 8192 || s.height > 8192)
    return fail("option --size: '" + text + "' is not WxH with 1..8192 pixels per side");
  return s;
}

Result<CommandLine> splitCommandLine(const std::vector<std::string>& argv) {
  CommandLine line;
  std::vector<std::string> globals;
  std::size_t i = 0;
  for (; i < argv.size(); ++i) {
    const std::string& word = argv[i];
    if (!isFlagWord(word) || !globalOptions().count(optionName(word))) break;
    globals.push_back(word);
    if (word.find('=') == std::string::npos) {
      if (i + 1 >= argv.size()) return fail("option " + word + " needs a value");
      globals.push_back(argv[++i]);
    }
  }
  if (i < argv.size()) {
    const std::string& word = argv[i];
    const bool help = word == "--help" || word == "-h" || word == "help" || word == "--version";
    if (!help && str::startsWith(word, "-")) {
      line.command = "desktop";  // desktop options without a command
    } else {
      line.command = word;
      ++i;
    }
  }
  line.args.assign(argv.begin() + std::ptrdiff_t(i), argv.end());
  line.args.insert(line.args.end(), globals.begin(), globals.end());
  return line;
}

Result<Args> Args::parse(const std::vector<std::string>& argv, const std::set<std::string>& valued,
                         const std::set<std::string>& flags) {
  Args args;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (isFlagWord(a)) {
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
      } else if (valued.count(name) || globalOptions().count(name)) {
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
  if (auto db = args.value("db"))
    if (auto st = checkDatabasePath(*db); !st) return tl::unexpected(st.error());
  if (auto user = args.value("user"); user && str::trim(*user).empty()) return fail("option --user needs a name");
  if (auto size = args.value("size")) {
    auto parsed = parsePixelSize(*size);
    if (!parsed) return tl::unexpected(parsed.error());
    args.size_ = *parsed;
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
