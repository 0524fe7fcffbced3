#include "gdrhcr/params.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace gdrhcr {

std::string Params::canonical(const std::string& key) {
  std::string k = key;
  for (char& c : k) {
    if (c == '_') c = '-';
    else if (key.size() > 1 && c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  }
  return k;
}

const std::string* Params::lookup(const std::string& raw) {
  const std::string key = canonical(raw);
  used_.insert(key);
  auto it = values_.find(key);
  return it == values_.end() ? nullptr : &it->second;
}

int Params::get_int(const std::string& key, int fallback, int min, int max) {
  const std::string* v = lookup(key);
  if (!v) return fallback;
  char* end = nullptr;
  errno = 0;
  long x = std::strtol(v->c_str(), &end, 10);
  if (v->empty() || *end != '\0' || errno == ERANGE)
    throw ParamError("parameter " + key + " must be an integer, got '" + *v + "'");
  if (x < min || x > max)
    throw ParamError("parameter " + key + " must be in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "], got " + *v);
  return static_cast<int>(x);
}

double Params::get_double(const std::string& key, double fallback, double min, double max) {
  const std::string* v = lookup(key);
  if (!v) return fallback;
  char* end = nullptr;
  double x = std::strtod(v->c_str(), &end);
  if (v->empty() || *end != '\0' || !std::isfinite(x))
    throw ParamError("parameter " + key + " must be a finite number, got '" + *v + "'");
  if (x < min || x > max) {
    char range[64];
    std::snprintf(range, sizeof range, "[%g, %g]", min, max);
    throw ParamError("parameter " + key + " must be in " + range + ", got " + *v);
  }
  return x;
}

uint64_t Params::get_u64(const std::string& key, uint64_t fallback) {
  const std::string* v = lookup(key);
  if (!v) return fallback;
  char* end = nullptr;
  errno = 0;
  unsigned long long x = std::strtoull(v->c_str(), &end, 10);
  if (v->empty() || (*v)[0] == '-' || *end != '\0' || errno == ERANGE)
    throw ParamError("parameter " + key + " must be a non-negative integer, got '" + *v + "'");
  return x;
}

std::string Params::get_string(const std::string& key, const std::string& fallback) {
  const std::string* v = lookup(key);
  return v ? *v : fallback;
}

std::string Params::get_choice(const std::string& key, const std::string& fallback,
                               const std::vector<std::string>& choices) {
  std::string v = get_string(key, fallback);
  for (auto& c : choices)
    if (c == v) return v;
  std::string all;
  for (auto& c : choices) all += (all.empty() ? "" : ", ") + c;
  throw ParamError("parameter " + key + " must be one of " + all + ", got '" + v + "'");
}

std::vector<std::string> Params::unused() const {
  std::vector<std::string> out;
  for (auto& [k, v] : values_)
    if (!used_.count(k)) out.push_back(k);
  return out;
}

void Params::check_all_used(const std::string& context) const {
  auto u = unused();
  if (u.empty()) return;
  std::string all;
  for (auto& k : u) all += (all.empty() ? "" : ", ") + k;
  throw ParamError("unknown parameter(s) for " + context + ": " + all);
}

}  // namespace gdrhcr
