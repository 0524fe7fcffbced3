// Replaces the LoRR Start-Kit's inc/MAPFPlanner.h (v1.1.5, same public interface): the Start-Kit
// builds this MAPFPlanner, whose initialize and plan run our planner through lorr_bridge.hpp.
// scripts/bench_lorr.sh copies the Start-Kit out of tree and puts this file in its place.
#pragma once
#include <ctime>
#include <memory>

#include "ActionModel.h"
#include "SharedEnv.h"
#include "lorr_bridge.hpp"

class MAPFPlanner {
 public:
  SharedEnvironment* env;

  MAPFPlanner(SharedEnvironment* env) : env(env) {}
  MAPFPlanner() { env = new SharedEnvironment(); }
  virtual ~MAPFPlanner();

  virtual void initialize(int preprocess_time_limit);

  // The next action of every agent, within time_limit seconds.
  virtual void plan(int time_limit, std::vector<Action>& plan);

 private:
  std::unique_ptr<gdrhcr_lorr::Bridge> bridge_;
};
