#include "gd_rhcr_planner/fleet_stats.hpp"

namespace gd_rhcr_planner {

namespace {
template <class T>
T read(const nlohmann::json& j, const char* key) {
  if (!j.is_object()) return T{};
  auto it = j.find(key);
  if (it == j.end() || !it->is_number()) return T{};
  return it->get<T>();
}
}  // namespace

PlannerFigures planner_figures(const nlohmann::json& s) {
  PlannerFigures f;
  f.pbs_nodes = read<uint64_t>(s, "pbs_nodes");
  if (s.contains("primary_calls")) {  // GD-RHCR
    f.solver_calls = read<uint64_t>(s, "primary_calls");
    f.solver_failures = read<uint64_t>(s, "failure_fallbacks");
    f.solver_time_mean = read<double>(s, "primary_time_mean_s");
  } else {  // RHCR
    f.solver_calls = read<uint64_t>(s, "solver_calls");
    f.solver_failures = read<uint64_t>(s, "solver_failures");
    f.solver_time_mean = read<double>(s, "solver_time_mean_s");
  }
  f.solver_timeouts = s.contains("timeouts") ? read<uint64_t>(s, "timeouts") : read<uint64_t>(s, "solver_timeouts");
  if (s.is_object() && s.contains("groups")) {
    const auto& g = s["groups"];
    f.groups_mean_count = read<double>(g, "mean_count");
    f.groups_mean_size = read<double>(g, "mean_size");
    f.groups_replanned_per_step = read<double>(g, "replanned_per_step");
  }
  f.cache_reuses = read<uint64_t>(s, "cache_reuses");
  f.threshold_fallbacks = read<uint64_t>(s, "threshold_fallbacks");
  f.failure_fallbacks = read<uint64_t>(s, "failure_fallbacks");
  f.repairs = read<uint64_t>(s, "repairs");
  f.pibt_swaps = read<uint64_t>(s, "swaps");
  return f;
}

void ThroughputMeter::add(double now, uint64_t delivered) {
  samples_.emplace_back(now, delivered);
  while (samples_.size() > 2 && samples_[1].first <= now - window_) samples_.pop_front();
}

double ThroughputMeter::per_minute() const {
  if (samples_.size() < 2) return 0;
  const double dt = samples_.back().first - samples_.front().first;
  if (dt <= 0) return 0;
  return 60.0 * static_cast<double>(samples_.back().second - samples_.front().second) / dt;
}

}  // namespace gd_rhcr_planner
