// The benchmarks' command lines (delay_benchmark, dispatch_benchmark): `--name value` pairs, read
// strictly. An unknown option, an option without its value, or a value that is not a number of
// the option's type or lies outside its range is an error (BenchOptionError) naming the option,
// so a typo never runs a benchmark with another setting than the one asked for.
#pragma once

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace gd_rhcr_planner {

class BenchOptionError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class BenchOptions {
 public:
  // `names`: the options the program takes (without the leading "--"); -h and --help are flags.
  BenchOptions(int argc, char** argv, const std::vector<std::string>& names) {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "-h" || a == "--help") {
        help_ = true;
        continue;
      }
      const std::string name = a.rfind("--", 0) == 0 ? a.substr(2) : std::string();
      bool known = false;
      for (const std::string& n : names) known |= n == name;
      if (!known) throw BenchOptionError("unknown option '" + a + "' (--help lists the options)");
      if (i + 1 >= argc) throw BenchOptionError("option --" + name + " needs a value");
      values_[name].push_back(argv[++i]);
    }
  }

  bool help() const { return help_; }
  // The option's value (the last one given), or `fallback`.
  std::string text(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second.back();
  }
  // Every value of a repeatable option, in order.
  std::vector<std::string> all(const std::string& name) const {
    auto it = values_.find(name);
    return it == values_.end() ? std::vector<std::string>{} : it->second;
  }
  // An integer in [lo, hi], or `fallback` when the option is not given.
  long integer(const std::string& name, long fallback, long lo, long hi) const {
    auto it = values_.find(name);
    if (it == values_.end()) return fallback;
    const std::string& v = it->second.back();
    char* end = nullptr;
    errno = 0;
    const long x = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || errno == ERANGE || x < lo || x > hi)
      throw BenchOptionError("--" + name + " must be an integer in [" + std::to_string(lo) + ", " +
                             std::to_string(hi) + "], not '" + v + "'");
    return x;
  }
  // A finite number in [lo, hi], or `fallback` when the option is not given.
  double real(const std::string& name, double fallback, double lo, double hi) const {
    auto it = values_.find(name);
    if (it == values_.end()) return fallback;
    const std::string& v = it->second.back();
    char* end = nullptr;
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(x) || x < lo || x > hi) {
      char range[64];
      std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
      throw BenchOptionError("--" + name + " must be a number in " + range + ", not '" + v + "'");
    }
    return x;
  }

 private:
  bool help_ = false;
  std::map<std::string, std::vector<std::string>> values_;
};

}  // namespace gd_rhcr_planner
