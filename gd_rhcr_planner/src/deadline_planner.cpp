#include "gd_rhcr_planner/deadline_planner.hpp"

#include <chrono>

namespace gd_rhcr_planner {

// One primary step: the worker owns copies of the world's vectors, since the tick that asked
// for it may have moved on by the time the planner returns.
struct DeadlinePlanner::Job {
  const gdrhcr::Grid* grid;
  const gdrhcr::DistTable* dist;
  int timestep;
  std::vector<gdrhcr::Cell> positions;
  std::vector<std::vector<gdrhcr::Cell>> goals;
  std::vector<uint8_t> immovable;
  bool has_immovable = false;
  std::vector<gdrhcr::Cell> blocked;
  bool has_blocked = false;
  gdrhcr::ActionModel action_model = gdrhcr::ActionModel::kMapf;
  std::vector<gdrhcr::Heading> headings, next_headings;  // rotation
  std::shared_ptr<const void> keep_alive;
  std::vector<gdrhcr::Cell> next;
  gdrhcr::StepReport report;
  std::string error;
  bool started = false, done = false;
};

DeadlinePlanner::DeadlinePlanner(std::unique_ptr<gdrhcr::Planner> primary,
                                 std::unique_ptr<gdrhcr::Planner> fallback)
    : primary_(std::move(primary)), fallback_(std::move(fallback)) {
  worker_ = std::thread([this] { worker_loop(); });
}

DeadlinePlanner::~DeadlinePlanner() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  worker_.join();
}

void DeadlinePlanner::worker_loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    cv_.wait(lock, [this] { return stop_ || (job_ && !job_->started); });
    if (job_ && !job_->started) {
      std::shared_ptr<Job> job = job_;
      job->started = true;
      lock.unlock();
      gdrhcr::WorldView world{*job->grid, *job->dist, job->timestep, job->positions, job->goals};
      if (job->has_immovable) world.immovable = &job->immovable;
      if (job->has_blocked) world.blocked = &job->blocked;
      world.action_model = job->action_model;
      if (world.rotation()) world.headings = &job->headings, world.next_headings = &job->next_headings;
      try {
        job->report = primary_->plan_step(world, job->next);
      } catch (const std::exception& e) {
        job->error = e.what();
      }
      lock.lock();
      job->keep_alive.reset();
      job->done = true;
      cv_.notify_all();
    }
    if (stop_) return;
  }
}

bool DeadlinePlanner::primary_idle() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return !job_ || job_->done;
}

void DeadlinePlanner::wait_idle() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [this] { return !job_ || job_->done; });
}

DeadlineOutcome DeadlinePlanner::step(const gdrhcr::WorldView& world, std::vector<gdrhcr::Cell>& next,
                                      double deadline_s, std::shared_ptr<const void> keep_alive) {
  DeadlineOutcome out;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (job_ && !job_->done) {
      out.primary_busy = true;
    } else {
      auto job = std::make_shared<Job>();
      job->grid = &world.grid;
      job->dist = &world.dist;
      job->timestep = world.timestep;
      job->positions = world.positions;
      job->goals = world.goals;
      if (world.immovable) job->immovable = *world.immovable, job->has_immovable = true;
      if (world.blocked) job->blocked = *world.blocked, job->has_blocked = true;
      job->action_model = world.action_model;
      if (world.rotation()) job->headings = *world.headings, job->next_headings = *world.next_headings;
      job->keep_alive = std::move(keep_alive);
      job->next = next;
      job_ = job;
      cv_.notify_all();
      auto finished = [&] { return job->done; };
      if (deadline_s > 0) {
        cv_.wait_for(lock, std::chrono::duration<double>(deadline_s), finished);
      } else {
        cv_.wait(lock, finished);
      }
      if (job->done && job->error.empty()) {
        next = job->next;
        if (world.rotation()) *world.next_headings = job->next_headings;
        out.report = job->report;
        return out;
      }
      if (job->done) out.primary_error = job->error;
      else out.primary_late = true;
    }
  }
  out.fallback = true;
  out.report = fallback_->plan_step(world, next);
  return out;
}

}  // namespace gd_rhcr_planner
