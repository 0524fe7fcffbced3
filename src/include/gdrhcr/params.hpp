// Named parameters with validation, shared by the command line and the ROS node. Each reader
// checks its type and range and names the parameter in its error; `unused()` lists parameters
// nobody read, so a typo ("--c_sotf") is reported instead of silently ignored.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace gdrhcr {

class ParamError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

class Params {
 public:
  // Keys are canonical: '_' reads as '-' and names longer than one letter are lower case, so
  // the paper's and ROS's spellings (c_soft, K_threshold, node_budget) name the same parameter
  // as the command line's (c-soft, k-threshold, node-budget); one-letter names (V, H) keep case.
  static std::string canonical(const std::string& key);
  void set(const std::string& key, const std::string& value) { values_[canonical(key)] = value; }
  bool has(const std::string& key) const { return values_.count(canonical(key)) > 0; }
  void erase(const std::string& key) { values_.erase(canonical(key)); }

  int get_int(const std::string& key, int fallback, int min, int max);
  double get_double(const std::string& key, double fallback, double min, double max);
  uint64_t get_u64(const std::string& key, uint64_t fallback);
  std::string get_string(const std::string& key, const std::string& fallback);
  std::string get_choice(const std::string& key, const std::string& fallback,
                         const std::vector<std::string>& choices);

  std::vector<std::string> unused() const;
  // Throws ParamError naming the unread parameters, if any.
  void check_all_used(const std::string& context) const;

 private:
  const std::string* lookup(const std::string& key);
  std::map<std::string, std::string> values_;
  std::set<std::string> used_;
};

}  // namespace gdrhcr
