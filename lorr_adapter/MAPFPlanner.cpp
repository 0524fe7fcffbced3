// Replaces the LoRR Start-Kit's src/MAPFPlanner.cpp (v1.1.5): our planner as the Start-Kit's
// MAPFPlanner. initialize builds it on the Start-Kit's map (settings from the environment, see
// lorr_bridge.hpp); plan hands it every agent's state and revealed goals and returns the
// Start-Kit's actions. A failure of our planner ends the run with exit code 3 and the reason on
// standard error, rather than letting the robots wait silently.
#include <MAPFPlanner.h>

#include <cstdio>
#include <exception>
#include <unistd.h>

namespace {
[[noreturn]] void fail(const char* where, const std::exception& e) {
  std::fprintf(stderr, "gdrhcr lorr adapter: %s failed: %s\n", where, e.what());
  std::fflush(stderr);
  _exit(3);
}
}  // namespace

MAPFPlanner::~MAPFPlanner() { delete env; }

void MAPFPlanner::initialize(int preprocess_time_limit) {
  try {
    gdrhcr_lorr::BridgeOptions options = gdrhcr_lorr::bridge_options_from_env();
    options.preprocess_s = preprocess_time_limit;
    bridge_ = std::make_unique<gdrhcr_lorr::Bridge>(env->rows, env->cols, env->map, env->num_of_agents, options);
  } catch (const std::exception& e) {
    fail("initialize", e);
  }
}

void MAPFPlanner::plan(int time_limit, std::vector<Action>& actions) {
  const int n = env->num_of_agents;
  std::vector<int> locations(n), headings(n), out;
  std::vector<std::vector<int>> goals(n);
  for (int i = 0; i < n; ++i) {
    locations[i] = env->curr_states[i].location;
    headings[i] = env->curr_states[i].orientation;
    for (auto& g : env->goal_locations[i]) goals[i].push_back(g.first);
  }
  try {
    bridge_->plan(env->curr_timestep, time_limit, locations, headings, goals, out);
  } catch (const std::exception& e) {
    fail("plan", e);
  }
  actions.assign(n, Action::W);
  for (int i = 0; i < n; ++i) actions[i] = static_cast<Action>(out[i]);
}
