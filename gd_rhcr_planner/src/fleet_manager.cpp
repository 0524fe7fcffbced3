// The fleet manager (fleet_manager.hpp): the planner node's logic without ROS.
#include "gd_rhcr_planner/fleet_manager.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <numeric>
#include <sstream>

#include "gdrhcr/map_prep.hpp"

namespace gd_rhcr_planner {
namespace {

std::string number(double x) {
  std::ostringstream o;
  o.precision(6);
  o << x;
  return o.str();
}

// The planner parameters dynamic_reconfigure changes (LiveConfig), canonical names.
constexpr const char* kLiveNames[] = {"V", "H", "c-soft", "k-threshold", "solver"};

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

void FleetConfig::validate() {
  if (!(tick_rate > 0 && tick_rate <= 1000)) throw gdrhcr::ParamError("~tick_rate must be in (0, 1000] Hz");
  if (plan_deadline == 0) plan_deadline = 0.7 / tick_rate;
  if (!(plan_deadline > 0 && plan_deadline <= 1.0 / tick_rate))
    throw gdrhcr::ParamError("~plan_deadline must be in (0, 1/tick_rate] seconds (0 = 0.7/tick_rate)");
  if (!(offline_timeout > 0)) throw gdrhcr::ParamError("~offline_timeout must be > 0 seconds");
  if (!(dispatch_rate >= 0 && dispatch_rate <= 1000))
    throw gdrhcr::ParamError("~dispatch_rate must be in [0, 1000] Hz (0 = moves are dispatched at ticks only)");
  if (num_robots < 1) throw gdrhcr::ParamError("~num_robots must be >= 1");
  if (dist_budget_mb < 1) throw gdrhcr::ParamError("~dist_budget_mb must be >= 1");
  if (commit_horizon < 1) throw gdrhcr::ParamError("~commit_horizon must be >= 1");
  if (catch_up < 0) throw gdrhcr::ParamError("~catch_up must be >= 0 (0 = off)");
  parse_dispatch_policy(dispatcher);  // throws naming a bad value
  dispatch.validate();
  gdrhcr::planner_param_specs(planner);  // throws naming an unknown planner
  model();                                // throws naming a bad action model
}

gdrhcr::ActionModel FleetConfig::model() const {
  try {
    return gdrhcr::parse_action_model(action_model);
  } catch (const std::invalid_argument& e) {
    throw gdrhcr::ParamError(std::string("~action_model: ") + e.what());
  }
}

gdrhcr::Params live_planner_params(const std::string& planner, const LiveConfig& c) {
  gdrhcr::Params p;
  auto put = [&](const char* name, const std::string& value) {
    if (gdrhcr::planner_has_param(planner, name)) p.set(name, value);
  };
  put("V", std::to_string(c.V));
  put("H", std::to_string(c.H));
  std::ostringstream cs;
  cs.precision(17);
  cs << c.c_soft;
  put("c_soft", cs.str());
  if (c.K_threshold > 0) put("K_threshold", std::to_string(c.K_threshold));
  put("solver", c.solver);
  return p;
}

// ---------------------------------------------------------------------------------------------
// Construction.

FleetManager::FleetManager(const gdrhcr::Grid& grid, FleetConfig cfg, Log sink)
    : grid_(grid), cfg_(std::move(cfg)), log_(std::move(sink)), operator_(std::max(cfg_.num_robots, 1)) {
  cfg_.validate();
  if (static_cast<size_t>(cfg_.num_robots) > grid_.free_cells().size())
    throw gdrhcr::ParamError("~num_robots exceeds the free cells of the map");
  // GD-RHCR returns within 90% of the plan deadline (groups it cannot solve in time go to its
  // secondary solver), so the fallback PIBT moves the whole fleet only when even that is late.
  auto_step_budget_ = gdrhcr::planner_has_param(cfg_.planner, "step-budget") && !cfg_.planner_params.has("step-budget");
  if (auto_step_budget_) cfg_.planner_params.set("step-budget", number(kStepBudgetShare * cfg_.plan_deadline));
  // The live values start from the given ones, else the table's.
  live_.plan_deadline = cfg_.plan_deadline;
  live_.offline_timeout = cfg_.offline_timeout;
  live_.dispatcher = cfg_.dispatcher;
  live_.dispatch_switch_margin = cfg_.dispatch.switch_margin;
  live_.dispatch_finish_horizon = cfg_.dispatch.finish_horizon;
  gdrhcr::Params given = cfg_.planner_params;
  apply_prep(given);
  const auto values = gdrhcr::PlannerParams::resolve(cfg_.planner, given, gdrhcr::MapFacts(grid_, cfg_.num_robots, cfg_.model()));
  given.check_all_used("planner " + cfg_.planner);  // a parameter the planner lacks is an error naming it
  dist_ = std::make_unique<gdrhcr::DistTable>(grid_, cfg_.model(), size_t(cfg_.dist_budget_mb) << 20,
                                              gdrhcr::step_costs(values, cfg_.model()));
  if (values.has("V")) live_.V = values.integer("V");
  if (values.has("H")) live_.H = values.integer("H");
  if (values.has("c-soft")) live_.c_soft = values.real("c-soft");
  if (cfg_.planner_params.has("k-threshold")) live_.K_threshold = values.integer("k-threshold");
  if (values.has("solver")) live_.solver = values.text("solver");
  base_params_ = cfg_.planner_params;
  for (const char* n : kLiveNames) base_params_.erase(n);
  planner_ = make_deadline_planner(gdrhcr::make_planner(values, grid_, cfg_.num_robots, cfg_.seed, cfg_.model()));
  fleet_ = std::make_unique<Fleet>(grid_, *dist_, cfg_.num_robots);
  fleet_->set_auto_assign(false);  // the dispatcher assigns
  ExecutorConfig ec;
  ec.commit_horizon = cfg_.commit_horizon;
  ec.catch_up = cfg_.catch_up;
  ec.plan_deadline_s = cfg_.plan_deadline;
  ec.dist_budget_bytes = size_t(cfg_.dist_budget_mb) << 20;
  ec.action_model = cfg_.model();
  executor_ = std::make_unique<Executor>(grid_, *dist_, cfg_.num_robots, ec);
  dispatcher_ = std::make_unique<Dispatcher>(parse_dispatch_policy(cfg_.dispatcher), cfg_.dispatch);
  if (cfg_.task_store.empty()) {
    log(LogLevel::kInfo, "task store off (~task_store: none): tasks do not survive a restart");
    return;
  }
  store_ = std::make_unique<TaskStore>(cfg_.task_store);  // throws on a damaged store
  snapshot_path_ = cfg_.task_store + ".robots";
  read_snapshot();
  const auto& saved = store_->loaded();
  for (auto& w : saved.warnings) log(LogLevel::kWarn, w);
  const size_t n = fleet_->restore(saved.open, saved.delivered, saved.failed, saved.next_id);
  log(LogLevel::kInfo, "task store " + cfg_.task_store + ": " + std::to_string(n) + " open tasks restored (" +
                           std::to_string(saved.open.size()) + " in the store)");
}

FleetManager::~FleetManager() = default;

size_t FleetManager::prepare_distances(const std::vector<Cell>& cells) {
  std::lock_guard<std::mutex> lock(mutex_);
  dist_->prefetch(cells);
  return dist_->cached_rows();
}

std::unique_ptr<DeadlinePlanner> FleetManager::make_deadline_planner(std::unique_ptr<gdrhcr::Planner> primary) const {
  gdrhcr::Params none;
  return std::make_unique<DeadlinePlanner>(std::move(primary),
                                           gdrhcr::make_planner("pibt", none, grid_, cfg_.num_robots, cfg_.seed, cfg_.model()));
}

// The offline preparation file (~prep_file), made by `gdrhcr_sim --prepare`: its traffic cost
// joins the planner's parameters unless they set one. Optional: a file that is missing or made
// for another map, fleet size or model is reported and the node runs without it.
void FleetManager::apply_prep(gdrhcr::Params& given) const {
  if (cfg_.prep_file.empty()) return;
  try {
    const auto prep = gdrhcr::load_prep(cfg_.prep_file, grid_, cfg_.num_robots, cfg_.model());
    const bool applied = gdrhcr::planner_has_param(cfg_.planner, "traffic-cost") && prep.apply(given) > 0;
    log(LogLevel::kInfo, "preparation " + cfg_.prep_file + ": traffic-cost " + number(prep.traffic_cost) +
                             (applied ? "" : " (not applied: set in planner_params or not a parameter of the planner)"));
  } catch (const gdrhcr::PrepError& e) {
    log(LogLevel::kWarn, std::string(e.what()) + "; running without it");
  }
}

void FleetManager::log(LogLevel level, const std::string& msg) const {
  if (log_) log_(level, msg);
}

void FleetManager::log_every(const std::string& key, double period, LogLevel level, const std::string& msg) {
  const double now = steady_seconds();
  auto it = last_logged_.find(key);
  if (it != last_logged_.end() && now - it->second < period) return;
  last_logged_[key] = now;
  log(level, msg);
}

void FleetManager::problem_locked(const std::string& what) {
  last_problem_ = what;
  last_problem_tick_ = tick_;
}

uint64_t FleetManager::tick_count() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return tick_;
}

// ---------------------------------------------------------------------------------------------
// Inputs.

bool FleetManager::update_robot(int64_t id, int x, int y, bool offline, bool moving, double now, std::string& error) {
  RobotReport r;
  r.id = id, r.x = x, r.y = y, r.mode = offline ? kOffline : kIdle, r.moving = moving;
  return update_robots({r}, now, error) == 0;
}

int FleetManager::update_robots(const std::vector<RobotReport>& reports, double now, std::string& error) {
  std::lock_guard<std::mutex> lock(mutex_);
  last_stamp_.resize(fleet_->num_robots(), 0.0);
  std::map<int64_t, int> seen;
  for (const RobotReport& r : reports) ++seen[r.id];
  int ignored = 0;
  for (const RobotReport& r : reports) {
    std::string why;
    const bool known = r.id >= 0 && r.id < fleet_->num_robots();
    if (known && seen[r.id] > 1) why = "robot " + std::to_string(r.id) + " is in one message twice";
    else if (!r.pose_finite) why = "robot " + std::to_string(r.id) + ": the pose is not finite";
    else if (r.mode > kModeStopped) why = "robot " + std::to_string(r.id) + ": unknown mode " + std::to_string(r.mode);
    else if (known && r.stamp > 0 && r.stamp < last_stamp_[r.id])
      why = "robot " + std::to_string(r.id) + ": stamped before its last report (out of order)";
    else if (r.heading != gdrhcr::kNoHeading && (r.heading < 0 || r.heading >= gdrhcr::kNumHeadings))
      why = "robot " + std::to_string(r.id) + ": unknown heading (RobotState.heading is HEADING_NONE 0 .. HEADING_NORTH 4)";
    else if (r.heading == gdrhcr::kNoHeading && cfg_.model() == gdrhcr::ActionModel::kRotation && r.mode != kOffline)
      why = "robot " + std::to_string(r.id) + " reports no heading (HEADING_NONE): ~action_model rotation needs it";
    else if (fleet_->update_robot(r.id, r.x, r.y, r.mode == kOffline, r.moving, why, now,
                                  r.entering_known ? std::make_optional(std::make_pair(r.entering_x, r.entering_y))
                                                   : std::nullopt,
                                  r.heading)) {
      if (r.stamp > 0) last_stamp_[r.id] = r.stamp;
      continue;
    }
    ++ignored;
    ++bad_reports_;
    last_ignored_ = why;
    error = why;
    log_every("report", 2.0, LogLevel::kWarn, "ignoring robot state: " + why);
  }
  return ignored;
}

SubmitResult FleetManager::submit(const TaskRequest& t) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto r = fleet_->submit(t.pickup_x, t.pickup_y, t.delivery_x, t.delivery_y, t.priority, t.id);
  if (!r.accepted) {
    ++rejected_tasks_;
    last_rejected_task_ = "task " + std::to_string(r.task_id) + ": " + r.reason;
    log_every("task rejected", 1.0, LogLevel::kWarn, "task " + std::to_string(r.task_id) + " rejected: " + r.reason);
  }
  return r;
}

bool FleetManager::cancel(uint64_t task_id, std::string& reason) {
  std::lock_guard<std::mutex> lock(mutex_);
  return fleet_->cancel(task_id, reason);
}

std::vector<std::pair<uint64_t, TaskRecord>> FleetManager::tasks(bool include_finished) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<std::pair<uint64_t, TaskRecord>> out;
  for (auto& [id, t] : fleet_->tasks())
    if (include_finished || !task_finished(t.state)) out.emplace_back(id, t);
  return out;
}

std::vector<TaskEvent> FleetManager::take_events() {
  std::lock_guard<std::mutex> lock(mutex_);
  auto events = fleet_->take_events();
  if (store_ && !events.empty()) {
    try {  // before anyone hears of the change, so an accepted task is on disk when accepted
      store_->record(events, *fleet_);
    } catch (const std::exception& e) {
      ++store_errors_;
      problem_locked(e.what());
      log_every("store", 2.0, LogLevel::kError,
                std::string(e.what()) + "; tasks are kept in memory but will not survive a restart");
    }
  }
  for (auto& e : events)
    if (e.state == kFailed || e.state == kCancelled)
      log(LogLevel::kInfo, "task " + std::to_string(e.task_id) + " " + task_state_name(e.state) +
                               (e.reason.empty() ? "" : ": " + e.reason));
  return events;
}

int FleetManager::distance_left(uint64_t task_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return fleet_->distance_left(task_id);
}

std::string FleetManager::set_paused(int64_t robot, bool paused) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string err = operator_.set_paused(robot, paused);
  if (err.empty())
    log(LogLevel::kInfo, std::string("operator: ") + (paused ? "pause " : "resume ") +
                             (robot < 0 ? "fleet" : "robot " + std::to_string(robot)) + "; now " + operator_.summary());
  else
    log(LogLevel::kWarn, "set_paused refused: " + err);
  return err;
}

void FleetManager::set_emergency_stop(bool engage) {
  std::lock_guard<std::mutex> lock(mutex_);
  operator_.set_emergency_stop(engage);
  if (engage) log(LogLevel::kWarn, "operator: EMERGENCY STOP engaged; every robot holds, tasks are kept");
  else log(LogLevel::kInfo, "operator: emergency stop released; now " + operator_.summary());
}

std::string FleetManager::operator_summary() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return operator_.summary();
}

// ---------------------------------------------------------------------------------------------
// Live tuning.

std::string FleetManager::config_string_locked(const LiveConfig& c) const {
  std::ostringstream o;
  o << "V=" << c.V << " H=" << c.H << " c_soft=" << c.c_soft << " K_threshold=" << c.K_threshold
    << " solver=" << c.solver;
  if (auto_step_budget_) o << " step_budget=" << number(kStepBudgetShare * c.plan_deadline);
  return o.str();
}

std::string FleetManager::planner_config_string() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return config_string_locked(live_);
}

LiveConfig FleetManager::live_config() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return config_pending_ ? pending_ : live_;
}

std::vector<std::string> FleetManager::reconfigure(LiveConfig& c) {
  std::vector<std::string> errors;
  const double period = 1.0 / cfg_.tick_rate;
  const LiveConfig live = live_config();
  if (c.plan_deadline == 0) c.plan_deadline = 0.7 * period;
  if (!(c.plan_deadline > 0 && c.plan_deadline <= period)) {
    errors.push_back("plan_deadline " + number(c.plan_deadline) + " s is outside (0, 1/tick_rate = " + number(period) +
                     " s]; keeping " + number(live.plan_deadline) + " s");
    c.plan_deadline = live.plan_deadline;
  }
  if (!(c.offline_timeout > 0)) {
    errors.push_back("offline_timeout must be > 0 s; keeping " + number(live.offline_timeout));
    c.offline_timeout = live.offline_timeout;
  }
  try {
    DispatchParams dp = cfg_.dispatch;
    dp.switch_margin = c.dispatch_switch_margin;
    dp.finish_horizon = c.dispatch_finish_horizon;
    dp.validate();
    parse_dispatch_policy(c.dispatcher);
  } catch (const std::exception& e) {
    errors.push_back(std::string(e.what()) + "; keeping dispatcher " + live.dispatcher);
    c.dispatcher = live.dispatcher;
    c.dispatch_switch_margin = live.dispatch_switch_margin;
    c.dispatch_finish_horizon = live.dispatch_finish_horizon;
  }
  std::unique_ptr<gdrhcr::Planner> fresh;
  std::string now_string, live_string;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    now_string = config_string_locked(c);
    live_string = config_string_locked(live);
  }
  if (now_string != live_string) {
    try {
      gdrhcr::Params p = base_params_;
      gdrhcr::Params changes = live_planner_params(cfg_.planner, c);
      for (const char* n : kLiveNames)
        if (changes.has(n)) p.set(n, changes.get_string(n, ""));
      if (auto_step_budget_) p.set("step-budget", number(kStepBudgetShare * c.plan_deadline));
      fresh = gdrhcr::make_planner(cfg_.planner, p, grid_, cfg_.num_robots, cfg_.seed, cfg_.model());
    } catch (const std::exception& e) {
      errors.push_back(std::string("planner parameters rejected (") + e.what() + "); keeping " + live_string);
      c.V = live.V, c.H = live.H, c.c_soft = live.c_soft, c.K_threshold = live.K_threshold, c.solver = live.solver;
    }
  }
  for (auto& e : errors) log(LogLevel::kError, "reconfigure: " + e);
  std::lock_guard<std::mutex> lock(mutex_);
  if (fresh) pending_planner_ = std::move(fresh);
  pending_ = c;
  config_pending_ = true;
  return errors;
}

// At the start of a tick: the planner built by reconfigure() replaces the running one (tasks stay
// in the Fleet; the new planner plans from the robots' cells). The old one is handed back to be
// destroyed outside the lock (it may wait for an abandoned step).
void FleetManager::apply_reconfigure_locked(std::unique_ptr<DeadlinePlanner>& retired) {
  if (!config_pending_) return;
  config_pending_ = false;
  const LiveConfig& c = pending_;
  if (pending_planner_) {
    retired = std::move(planner_);
    planner_ = make_deadline_planner(std::move(pending_planner_));
    ++reconfigures_;
    log(LogLevel::kInfo, "reconfigure: planner " + cfg_.planner + " now runs with " + config_string_locked(c) +
                             " (tick " + std::to_string(tick_) + ")");
  }
  cfg_.plan_deadline = c.plan_deadline;
  cfg_.offline_timeout = c.offline_timeout;
  DispatchParams dp = dispatcher_->params();
  dp.switch_margin = c.dispatch_switch_margin;
  dp.finish_horizon = c.dispatch_finish_horizon;
  if (c.dispatcher != dispatch_policy_name(dispatcher_->policy()) ||
      dp.switch_margin != dispatcher_->params().switch_margin ||
      dp.finish_horizon != dispatcher_->params().finish_horizon)
    dispatcher_ = std::make_unique<Dispatcher>(parse_dispatch_policy(c.dispatcher), dp);
  live_ = c;
}

// ---------------------------------------------------------------------------------------------
// The tick.

struct FleetManager::Gathered {
  uint64_t tick = 0;
  std::vector<std::vector<Cell>> goals;  // per robot (Fleet::fill_goals)
  std::vector<uint8_t> held;             // per robot: paused or stopped, no new move
  std::vector<RobotRecord> robots;
  bool proceed_without_missing = false;
};

// The start of a tick: a pending reconfigure, silent robots, the wait for robots that never
// reported, task dispatch, and a copy of what the execution layer needs.
FleetManager::Gathered FleetManager::gather_locked(double now, std::unique_ptr<DeadlinePlanner>& retired) {
  Gathered in;
  in.tick = ++tick_;
  apply_reconfigure_locked(retired);
  if (first_report_ > 0 && now - first_report_ >= cfg_.offline_timeout) place_unreported_locked(now);
  for (int r : fleet_->mark_silent(now, cfg_.offline_timeout))
    log(LogLevel::kWarn, "robot " + std::to_string(r) + " sent no state for " + number(cfg_.offline_timeout) +
                             " s: offline (an obstacle at its last cell); its task is requeued");
  // Robots that never reported are waited for ~offline_timeout after the first report, then left
  // out (taken to be off the floor); the rest of the fleet moves.
  const int missing = fleet_->missing_robots();
  if (missing < fleet_->num_robots() && first_report_ == 0) first_report_ = now;
  in.proceed_without_missing = first_report_ > 0 && now - first_report_ >= cfg_.offline_timeout;
  if (missing > 0 && in.proceed_without_missing) {
    problem_locked(std::to_string(missing) + " robots never reported a state: left out of planning");
    log_every("missing", 10.0, LogLevel::kWarn, last_problem_);
  }
  // Tasks move on only once the fleet does: robots without a cell must not be assigned anything.
  if (missing == 0 || in.proceed_without_missing) {
    fleet_->set_accepted_cells(executor_->accepted_cells());  // no pickup or delivery from a rejected report
    fleet_->advance();
    dispatch_stats_ = dispatcher_->dispatch(*fleet_, *dist_, operator_.unavailable());
  }
  fleet_->fill_goals(in.goals);
  robot_records_locked(in.robots, in.held);
  return in;
}

// After a restart, a robot that has not reported since is where the previous run last knew it
// (the robots' snapshot): it is placed there as an offline robot, an obstacle the fleet plans
// around and gives no task, instead of being left out (another robot would be sent through the
// cell it stands in); it falls silent if it stays quiet, and rejoins when it reports. One that
// was commanded into another cell is placed as moving, so the cells around it stay clear too.
void FleetManager::place_unreported_locked(double now) {
  for (const auto& [r, snap] : unreported_) {
    if (fleet_->robot(r).reported) continue;
    std::string err;
    const Cell c = snap.cell;
    std::optional<std::pair<int, int>> entering;
    if (snap.moving && snap.entering != gdrhcr::kNoCell)
      entering = std::make_pair(grid_.x_of(snap.entering), grid_.y_of(snap.entering));
    if (!fleet_->update_robot(r, grid_.x_of(c), grid_.y_of(c), true, snap.moving, err, now, entering, snap.heading) &&
        !fleet_->update_robot(r, grid_.x_of(c), grid_.y_of(c), true, snap.moving, err, now))
      continue;
    log(LogLevel::kWarn, "robot " + std::to_string(r) + " has not reported since the restart: an obstacle at " +
                             grid_.describe(c) + (entering ? " and " + grid_.describe(snap.entering) : std::string()) +
                             ", where it was last known, until it reports");
  }
  unreported_.clear();
}

// Where every placed robot is and whether it is commanded into another cell, for a successor
// after a restart; written next to the task journal (tmp file, then rename).
void FleetManager::write_snapshot_locked(const TickOutput& exec) const {
  if (snapshot_path_.empty()) return;
  const std::string tmp = snapshot_path_ + ".tmp";
  {
    std::ofstream f(tmp, std::ios::trunc);
    // robot, cell, moving, heading (-1: none), the cell it was commanded into (-1: none)
    for (size_t r = 0; r < exec.cells.size(); ++r) {
      if (exec.cells[r] == gdrhcr::kNoCell) continue;
      const bool moving = exec.command[r] != gdrhcr::kNoCell && exec.command[r] != exec.cells[r];
      const int heading = r < exec.headings.size() ? exec.headings[r] : gdrhcr::kNoHeading;
      f << r << ' ' << exec.cells[r] << ' ' << moving << ' ' << heading << ' '
        << (moving ? static_cast<long long>(exec.command[r]) : -1LL) << '\n';
    }
    if (!f) return;
  }
  std::rename(tmp.c_str(), snapshot_path_.c_str());
}

void FleetManager::read_snapshot() {
  std::ifstream f(snapshot_path_);
  const auto free_cell = [&](long long c) { return c >= 0 && c < grid_.num_cells() && grid_.is_free(static_cast<Cell>(c)); };
  for (std::string line; std::getline(f, line);) {  // heading and commanded cell: optional (older files)
    std::istringstream in(line);
    long long r = 0, cell = 0, entering = -1;
    int moving = 0, heading = gdrhcr::kNoHeading;
    if (!(in >> r >> cell >> moving) || r < 0 || r >= cfg_.num_robots || !free_cell(cell)) continue;
    if (!(in >> heading) || heading < gdrhcr::kNoHeading || heading > 3) heading = gdrhcr::kNoHeading;
    if (!(in >> entering) || !free_cell(entering)) entering = -1;
    LastKnown& k = unreported_[static_cast<int>(r)];
    k.cell = static_cast<Cell>(cell);
    k.moving = moving != 0;
    k.heading = static_cast<gdrhcr::Heading>(heading);
    k.entering = entering < 0 ? gdrhcr::kNoCell : static_cast<Cell>(entering);
  }
  if (!unreported_.empty())
    log(LogLevel::kInfo, "robots' snapshot " + snapshot_path_ + ": " + std::to_string(unreported_.size()) +
                             " robots' last cells (for those that do not report after the restart)");
}

// What the execution layer gets of each robot: its record, and whether it is held.
void FleetManager::robot_records_locked(std::vector<RobotRecord>& robots, std::vector<uint8_t>& held) const {
  robots.clear();
  robots.reserve(fleet_->num_robots());
  held.assign(fleet_->num_robots(), 0);
  for (int r = 0; r < fleet_->num_robots(); ++r) {
    robots.push_back(fleet_->robot(r));
    held[r] = operator_.holds(r);
  }
}

// Gather (locked), plan and execute (unlocked, so reports and services keep flowing), then
// count and report (locked).
TickResult FleetManager::tick(double now, double wall, bool view) {
  const double t0 = steady_seconds();
  std::unique_ptr<DeadlinePlanner> retired;  // destroyed unlocked, at return
  Gathered in;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    in = gather_locked(now, retired);
  }
  TickResult out;
  out.tick = in.tick;
  executor_->set_plan_deadline(cfg_.plan_deadline);
  const TickOutput exec = executor_->tick(in.robots, in.goals, *planner_, in.proceed_without_missing, &in.held);
  std::lock_guard<std::mutex> lock(mutex_);
  catch_up_moves_ += exec.caught_up;
  if (!exec.stepped) {
    ++skipped_;
    problem_locked(exec.skip_reason);
    out.skip_reason = exec.skip_reason;
    log_every("skip", 5.0, LogLevel::kInfo, "no step: " + exec.skip_reason);
    return out;
  }
  out.stepped = true;
  release_stuck_locked(exec, now);
  write_snapshot_locked(exec);
  for (const std::string& w : exec.warnings) log(LogLevel::kWarn, w);
  // The primary planner's groups and paths, when it planned this tick (else it may still be
  // running an abandoned step on its worker and must not be read).
  const gdrhcr::Planner* primary = exec.outcome.fallback ? nullptr : &planner_->primary();
  std::vector<int> group_of;
  groups_of(exec, primary, out, group_of);
  count_outcome_locked(exec);
  out.commands = commands_locked(exec.command, exec.command_heading);
  stats_locked(exec, primary, steady_seconds() - t0, wall, out);
  if (view) view_locked(exec, primary, group_of, in.goals, out);
  return out;
}

// A robot the executor has found inconsistent for longer than ~offline_timeout (its reports name a
// cell another robot holds, or one it cannot have reached) gives its task back, like a robot gone
// offline, and gets none until its reports fit again.
void FleetManager::release_stuck_locked(const TickOutput& exec, double now) {
  inconsistent_since_.resize(exec.health.size(), -1.0);
  for (size_t i = 0; i < exec.health.size(); ++i) {
    const int r = static_cast<int>(i);
    double& since = inconsistent_since_[i];
    if (exec.health[i] != RobotHealth::kInconsistent) {
      since = -1.0;
      if (fleet_->robot(r).stuck) {
        fleet_->set_stuck(r, false);
        log(LogLevel::kInfo, "robot " + std::to_string(r) + "'s reports fit again: it takes tasks again");
      }
      continue;
    }
    if (since < 0) since = now;
    if (now - since > cfg_.offline_timeout && !fleet_->robot(r).stuck) {
      fleet_->set_stuck(r, true);
      log(LogLevel::kWarn, "robot " + std::to_string(r) + "'s reports have not fitted for " +
                               number(cfg_.offline_timeout) + " s: its task is requeued, it gets none until they fit");
    }
  }
}

std::vector<RobotCommand> FleetManager::between_ticks() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (tick_ == 0) return {};
  std::vector<RobotRecord> robots;
  std::vector<uint8_t> held;
  robot_records_locked(robots, held);
  const std::vector<int> changed = executor_->advance(robots, &held);
  early_dispatches_ += changed.size();
  std::vector<Cell> command(fleet_->num_robots(), gdrhcr::kNoCell);
  std::vector<gdrhcr::Heading> heading(fleet_->num_robots(), gdrhcr::kNoHeading);
  for (int r : changed) command[r] = executor_->command(r), heading[r] = executor_->command_heading(r);
  return commands_locked(command, heading);
}

// Every robot's command (a robot that never reported gets none), with what it does to follow it
// from the pose the executor knows.
std::vector<RobotCommand> FleetManager::commands_locked(const std::vector<Cell>& command,
                                                        const std::vector<gdrhcr::Heading>& heading) const {
  std::vector<RobotCommand> out;
  for (size_t r = 0; r < command.size(); ++r) {
    if (command[r] == gdrhcr::kNoCell) continue;
    const int robot = static_cast<int>(r);
    RobotCommand c{robot, command[r], operator_.mode(robot, fleet_->command_mode(robot)), fleet_->task_of(robot),
                   heading[r]};
    c.action = command_action({executor_->cell(robot), executor_->heading(robot)}, c.cell, c.heading);
    out.push_back(c);
  }
  return out;
}

// Fallback ticks, deadline misses, planner errors and rejected steps.
void FleetManager::count_outcome_locked(const TickOutput& exec) {
  const DeadlineOutcome& outcome = exec.outcome;
  if (outcome.fallback) {
    ++fallback_ticks_;
    if (outcome.primary_late) {
      ++late_ticks_;
      log_every("late", 2.0, LogLevel::kWarn,
                "tick " + std::to_string(tick_) + ": " + cfg_.planner + " missed the " + number(cfg_.plan_deadline) +
                    " s plan deadline; PIBT moved the fleet");
    }
    if (!outcome.primary_error.empty()) {
      ++planner_errors_;
      problem_locked("planner failed, PIBT moved the fleet: " + outcome.primary_error);
      log_every("planner error", 1.0, LogLevel::kError, last_problem_);
    }
  }
  if (!exec.plan_error.empty()) {
    ++invalid_plans_;
    problem_locked("planner step rejected, all robots wait: " + exec.plan_error);
    log_every("rejected", 1.0, LogLevel::kError, last_problem_);
  }
}

// The planner's groups by robot id (group_of: each robot's group; a robot alone when none).
void FleetManager::groups_of(const TickOutput& exec, const gdrhcr::Planner* primary, TickResult& out,
                             std::vector<int>& group_of) const {
  group_of.resize(exec.cells.size());
  std::iota(group_of.begin(), group_of.end(), 0);
  if (!primary) return;
  const auto groups = primary->groups();
  for (size_t g = 0; g < groups.size(); ++g) {
    std::vector<int> members;
    for (int a : groups[g].agents) {
      if (a < 0 || a >= static_cast<int>(exec.robot_of_agent.size())) continue;
      const int r = exec.robot_of_agent[a];
      members.push_back(r);
      group_of[r] = static_cast<int>(g);
    }
    out.groups.push_back(std::move(members));
    out.group_solvers.push_back(groups[g].solver);
  }
}

}  // namespace gd_rhcr_planner

namespace gd_rhcr_planner {

// ---------------------------------------------------------------------------------------------
// Reporting.

void FleetManager::stats_locked(const TickOutput& exec, const gdrhcr::Planner* primary, double step_time,
                                double wall, TickResult& out) {
  const double period = 1.0 / cfg_.tick_rate;
  const gdrhcr::StepReport& report = exec.outcome.report;
  tick_walls_.push_back(wall);
  while (!tick_walls_.empty() && tick_walls_.front() < wall - 5.0) tick_walls_.pop_front();
  if (step_time > period) {
    ++overruns_;
    log_every("overrun", 2.0, LogLevel::kWarn, "tick " + std::to_string(tick_) + " took " + number(step_time) +
                                                   " s, longer than the period " + number(period) + " s");
  }
  last_plan_time_ = report.plan_time_s;
  plan_time_sum_ += report.plan_time_s;
  plan_time_max_ = std::max(plan_time_max_, report.plan_time_s);
  step_time_max_ = std::max(step_time_max_, step_time);
  ++plan_time_count_;
  throughput_.add(wall, fleet_->delivered_total());

  TickStats& st = out.stats;
  st.planner = cfg_.planner;
  st.num_robots = exec.cells.size();
  st.planned = report.planned;
  st.plan_time = report.plan_time_s;
  st.step_time = step_time;
  st.tick_period = period;
  st.overruns = overruns_;
  st.skipped_ticks = skipped_;
  st.forced_waits = exec.held + exec.waiting;
  st.tasks_queued = fleet_->count_in_state(kQueued);
  st.tasks_active = fleet_->count_in_state(kAssigned) + fleet_->count_in_state(kPicked);
  st.tasks_delivered = fleet_->delivered_total();
  st.tasks_failed = fleet_->failed_total();
  st.num_groups = out.groups.size();
  st.fallback_ticks = fallback_ticks_;
  st.fallback = exec.outcome.fallback;
  st.offline_robots = fleet_->offline_count();
  if (primary) {
    try {
      const auto js = primary->stats();
      st.planner_stats_json = js.dump();
      st.figures = planner_figures(js);
    } catch (const std::exception& e) {  // a planner's report must not stop the tick
      ++stats_errors_;
      problem_locked(std::string("planner statistics unreadable: ") + e.what());
      log_every("stats", 10.0, LogLevel::kWarn, last_problem_);
    }
  }
  st.planner_config = config_string_locked(live_);
  st.reconfigures = reconfigures_;
  st.deliveries_per_minute = throughput_.per_minute();
  size_t members = 0;
  for (auto& g : out.groups) {
    members += g.size();
    st.group_size_max = std::max<uint32_t>(st.group_size_max, g.size());
  }
  st.group_size_mean = out.groups.empty() ? 0.0 : double(members) / out.groups.size();
  st.dispatcher = dispatch_policy_name(dispatcher_->policy());
  st.dispatch = dispatch_stats_;
  st.paused_robots = operator_.paused_count();
  st.emergency_stop = operator_.emergency_stop();
}

void FleetManager::view_locked(const TickOutput& exec, const gdrhcr::Planner* primary,
                                  const std::vector<int>& group_of, const std::vector<std::vector<Cell>>& goals,
                                  TickResult& out) const {
  FleetView& v = out.view;
  const size_t n = exec.cells.size();
  v.pos = exec.cells;
  v.heading = exec.headings;
  v.next = exec.command;
  v.group_of = group_of;
  v.paths.assign(n, {});
  if (primary)
    for (size_t a = 0; a < exec.robot_of_agent.size(); ++a)
      v.paths[exec.robot_of_agent[a]] = primary->planned_path(static_cast<int>(a));
  v.goal.assign(n, gdrhcr::kNoCell);
  v.offline.assign(n, 0);
  v.held.assign(n, 0);
  for (size_t r = 0; r < n; ++r) {
    if (r < goals.size() && !goals[r].empty()) v.goal[r] = goals[r][0];
    v.offline[r] = fleet_->robot(r).offline;
    v.held[r] = operator_.paused(static_cast<int>(r));
  }
  v.emergency_stop = operator_.emergency_stop();
  size_t open = 0, queued = 0;
  for (auto& [id, t] : fleet_->tasks()) {
    if (task_finished(t.state)) continue;
    ++open;
    queued += t.state == kQueued;
    if (t.state != kPicked) v.task_pickups.push_back(t.pickup);
    else v.task_deliveries.push_back(t.delivery);
  }
  int groups = 0;
  for (int g : group_of) groups = std::max(groups, g + 1);
  v.overlay = overlay_text(tick_, throughput_.per_minute(), open, queued, groups, last_plan_time_, cfg_.planner,
                           dispatch_policy_name(dispatcher_->policy()), operator_.summary());
}

Health FleetManager::diagnose(double wall, std::vector<std::pair<std::string, std::string>>& values) {
  std::lock_guard<std::mutex> lock(mutex_);
  HealthCounters c;
  c.overruns = overruns_;
  c.rejected_plans = invalid_plans_;
  c.fallback_ticks = fallback_ticks_;
  c.store_errors = store_errors_;
  c.skipped_ticks = skipped_;
  c.missing_robots = fleet_->missing_robots();
  c.offline_robots = fleet_->offline_count();
  c.paused_robots = operator_.paused_count();
  c.emergency_stop = operator_.emergency_stop();
  const Health h = health_.update(c);
  double rate = 0;
  if (tick_walls_.size() >= 2 && wall - tick_walls_.front() < 6.0)
    rate = (tick_walls_.size() - 1) / (tick_walls_.back() - tick_walls_.front());
  auto add = [&](const std::string& k, const std::string& v) { values.emplace_back(k, v); };
  auto add_n = [&](const std::string& k, double v) { values.emplace_back(k, number(v)); };
  auto add_i = [&](const std::string& k, uint64_t v) { values.emplace_back(k, std::to_string(v)); };
  add("planner", cfg_.planner);
  add("planner config", config_string_locked(live_));
  add("dispatcher", dispatch_policy_name(dispatcher_->policy()));
  add("action model", gdrhcr::action_model_name(cfg_.model()));
  add("operator", operator_.summary());
  add_i("tick", tick_);
  add_n("tick rate target (Hz)", cfg_.tick_rate);
  add_n("tick rate measured (Hz)", rate);
  add_n("plan time mean (s)", plan_time_count_ ? plan_time_sum_ / plan_time_count_ : 0.0);
  add_n("plan time max (s)", plan_time_max_);
  add_n("tick callback max (s)", step_time_max_);
  add_i("overruns", overruns_);
  add_n("plan deadline (s)", cfg_.plan_deadline);
  add_n("offline timeout (s)", cfg_.offline_timeout);
  add_i("fallback ticks", fallback_ticks_);
  add_i("deadline misses", late_ticks_);
  add_i("planner errors", planner_errors_);
  add_i("planner statistics errors", stats_errors_);
  add_i("offline robots", fleet_->offline_count());
  add_i("paused robots", operator_.paused_count());
  add("task store", store_ ? store_->path() : std::string("off"));
  add_i("task store errors", store_errors_);
  add_i("skipped ticks", skipped_);
  add_i("rejected plans", invalid_plans_);
  add_i("ignored robot reports", bad_reports_);
  add("last ignored robot report", last_ignored_.empty() ? "none" : last_ignored_);
  add_i("rejected tasks", rejected_tasks_);
  add("last rejected task", last_rejected_task_.empty() ? "none" : last_rejected_task_);
  add("execution", "adg, commit horizon " + std::to_string(cfg_.commit_horizon) +
                       (cfg_.dispatch_rate > 0 ? ", dispatch on arrival" : ", dispatch at ticks") +
                       (cfg_.catch_up > 0 ? ", catch-up " + std::to_string(cfg_.catch_up) : ", no catch-up"));
  add_i("moves dispatched between ticks", early_dispatches_);
  add_i("moves made to catch up after delays", catch_up_moves_);
  // Memory that grows by design up to a bound: the distance rows (dist_budget_mb) and the
  // finished tasks kept for list_tasks.
  add_i("distance rows cached", dist_->cached_rows());
  add_n("distance cache (MB)", dist_->cached_bytes() / 1048576.0);
  add_i("tasks known", fleet_->tasks().size());
  add_i("tasks delivered", fleet_->delivered_total());
  add_i("tasks failed", fleet_->failed_total());
  add_n("deliveries per minute", throughput_.per_minute());
  add_i("planner reconfigurations", reconfigures_);
  add("last problem", last_problem_.empty() ? "none" : last_problem_);
  add_i("last problem at tick", last_problem_tick_);
  return h;
}

}  // namespace gd_rhcr_planner

namespace gd_rhcr_planner {

std::string default_task_store(const std::string& node_name) {
  std::string home;
  if (const char* h = std::getenv("ROS_HOME")) home = h;
  else if (const char* u = std::getenv("HOME")) home = std::string(u) + "/.ros";
  else home = "/tmp";
  std::string name = node_name;
  std::replace(name.begin(), name.end(), '/', '_');
  if (!name.empty() && name[0] == '_') name.erase(0, 1);
  return home + "/gd_rhcr_planner/" + name + ".tasks.jsonl";
}

const std::vector<std::string>& node_param_names() {
  static const std::vector<std::string> names = {
      "map", "planner", "frame_id", "cell_size", "tick_rate", "num_robots", "seed", "per_robot_topics",
      "publish_markers", "label_limit", "dist_budget_mb", "plan_deadline", "offline_timeout", "commit_horizon",
      "catch_up", "dispatch_rate", "show_goal_lines", "dispatcher", "dispatch_finish_horizon", "dispatch_switch_margin",
      "dispatch_max_tasks", "dispatch_age_weight", "task_store", "planner_params", "action_model",
      "prep_file"};
  return names;
}

NodeParamKind classify_node_param(const std::string& name, const std::string& planner) {
  const auto& own = node_param_names();
  if (std::find(own.begin(), own.end(), name) != own.end()) return NodeParamKind::kNode;
  if (gdrhcr::planner_has_param(planner, name)) return NodeParamKind::kPlanner;
  for (const std::string& other : gdrhcr::planner_names())
    if (gdrhcr::planner_has_param(other, name)) return NodeParamKind::kOtherPlanner;
  if (name == "execution")
    throw gdrhcr::ParamError("~execution was removed (issue 22): the ADG is the only execution; drop the parameter");
  throw gdrhcr::ParamError("unknown parameter ~" + name + ": not a parameter of the node nor of any planner (" +
                           "gdrhcr_sim --planner NAME --list-params lists a planner's)");
}

}  // namespace gd_rhcr_planner
