#include "gdrhcr/task_stream.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace gdrhcr {

uint64_t mix_seed(uint64_t seed, uint64_t stream) {
  uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

namespace {
Cell draw_other_than(const std::vector<Cell>& set, Cell current, std::mt19937_64& rng) {
  if (set.size() == 1) return set[0];
  // Rejection keeps the draw uniform over the set minus `current`.
  for (;;) {
    Cell c = set[std::uniform_int_distribution<size_t>(0, set.size() - 1)(rng)];
    if (c != current) return c;
  }
}

void require_free(const Grid& grid, int agent, Cell current, const char* stream) {
  if (!grid.is_free(current))
    throw std::invalid_argument(std::string(stream) + " task stream: agent " + std::to_string(agent) +
                                " is at " + grid.describe(current) + ", which is not a free cell");
}

void grow_rngs(std::vector<std::mt19937_64>& rngs, int agent, uint64_t seed, uint64_t salt) {
  if (agent < 0) throw std::out_of_range("task stream: negative agent id");
  while (static_cast<int>(rngs.size()) <= agent)
    rngs.emplace_back(mix_seed(seed ^ salt, rngs.size()));
}
}  // namespace

RandomNavigationStream::RandomNavigationStream(const Grid& grid, uint64_t seed)
    : grid_(grid), seed_(seed) {}

std::mt19937_64& RandomNavigationStream::rng(int agent) {
  grow_rngs(rngs_, agent, seed_, 0x52414e44ULL);
  return rngs_[agent];
}

Cell RandomNavigationStream::next_goal(int agent, Cell current) {
  require_free(grid_, agent, current, "random");
  // Only the current cell's component: any other goal could never be reached. On a connected
  // map this list is free_cells() itself, so the sequences are those of a plain uniform draw.
  return draw_other_than(grid_.component_cells(grid_.component(current)), current, rng(agent));
}

std::unique_ptr<TaskStream> RandomNavigationStream::clone_fresh() const {
  return std::make_unique<RandomNavigationStream>(grid_, seed_);
}

TaskListStream::TaskListStream(const Grid& grid, std::vector<Cell> tasks, int team_size, Strategy strategy)
    : grid_(grid), tasks_(std::move(tasks)), team_size_(team_size), strategy_(strategy) {
  if (team_size_ < 1) throw std::invalid_argument("task list: team size must be at least 1");
  if (tasks_.empty()) throw std::invalid_argument("task list: no tasks");
  for (size_t k = 0; k < tasks_.size(); ++k)
    if (!grid_.is_free(tasks_[k]))
      throw std::invalid_argument("task list: task " + std::to_string(k) + " at cell id " +
                                  std::to_string(tasks_[k]) + " is not a free cell of the map");
  if (strategy_ == Strategy::RoundRobinFixed) {  // agent a gets tasks a, a + n, ...: ceil((m - a) / n)
    const long m = static_cast<long>(tasks_.size()), n = team_size_;
    fixed_first_id_.assign(team_size_, 0);
    for (long a = 1; a < n; ++a) fixed_first_id_[a] = fixed_first_id_[a - 1] + (a - 1 < m ? (m - (a - 1) + n - 1) / n : 0);
  }
}

const char* TaskListStream::to_string(Strategy s) {
  switch (s) {
    case Strategy::RoundRobin: return "roundrobin";
    case Strategy::RoundRobinFixed: return "roundrobin_fixed";
    case Strategy::Greedy: return "greedy";
  }
  return "?";
}

TaskListStream::Strategy TaskListStream::parse_strategy(const std::string& s) {
  if (s == "roundrobin") return Strategy::RoundRobin;
  if (s == "roundrobin_fixed") return Strategy::RoundRobinFixed;
  if (s == "greedy") return Strategy::Greedy;
  throw std::invalid_argument("unknown task assignment strategy '" + s +
                              "' (expected roundrobin, roundrobin_fixed or greedy)");
}

const std::vector<long>& TaskListStream::assigned_ids(int agent) const {
  static const std::vector<long> none;
  return agent >= 0 && agent < static_cast<int>(ids_.size()) ? ids_[agent] : none;
}

Cell TaskListStream::next_goal(int agent, Cell current) {
  require_free(grid_, agent, current, "task list");
  if (agent < 0) throw std::out_of_range("task stream: negative agent id");
  if (agent >= team_size_)
    throw std::out_of_range("task list: agent " + std::to_string(agent) + " is not in the team of " +
                            std::to_string(team_size_));
  if (static_cast<int>(ids_.size()) <= agent) ids_.resize(agent + 1), next_round_.resize(agent + 1, 0);
  const long m = static_cast<long>(tasks_.size());
  long index = -1, id = -1;  // place in the list, Start-Kit id
  if (strategy_ == Strategy::Greedy) {
    if (next_shared_ < m) index = id = next_shared_++;
  } else {
    const long j = next_round_[agent]++;
    index = j * team_size_ + agent;
    if (strategy_ == Strategy::RoundRobin) id = next_id_++;
    else if (index < m) id = fixed_first_id_[agent] + j;
    else index = -1;
  }
  ids_[agent].push_back(id);
  return index < 0 ? current : tasks_[index % m];
}

bool TaskListStream::is_errand(int agent, Cell, Cell) const {
  const auto& ids = assigned_ids(agent);
  return !ids.empty() && ids.back() >= 0;
}

std::unique_ptr<TaskStream> TaskListStream::clone_fresh() const {
  return std::make_unique<TaskListStream>(grid_, tasks_, team_size_, strategy_);
}

void check_mapd_cells(const Grid& grid, const std::vector<Cell>& pickups,
                      const std::vector<Cell>& deliveries) {
  if (pickups.empty() || deliveries.empty())
    throw std::invalid_argument("MAPD task stream needs at least one pickup and one delivery cell");
  for (auto* set : {&pickups, &deliveries})
    for (Cell c : *set)
      if (!grid.is_free(c))
        throw std::invalid_argument("MAPD " + std::string(set == &pickups ? "pickup" : "delivery") +
                                    " cell " + grid.describe(c) + " is not a free cell");
  std::vector<char> has_pickup(grid.count_components(), 0), has_delivery(grid.count_components(), 0);
  for (Cell c : pickups) has_pickup[grid.component(c)] = 1;
  for (Cell c : deliveries) has_delivery[grid.component(c)] = 1;
  for (Cell c : pickups)
    if (!has_delivery[grid.component(c)])
      throw std::invalid_argument(
          "MAPD pickup cell " + grid.describe(c) + " cannot reach any delivery cell (its region of " +
          std::to_string(grid.component_cells(grid.component(c)).size()) +
          " free cells has none; the map has " + std::to_string(grid.count_components()) +
          " separate regions)");
  for (Cell c : deliveries)
    if (!has_pickup[grid.component(c)])
      throw std::invalid_argument(
          "MAPD delivery cell " + grid.describe(c) + " cannot reach any pickup cell (its region of " +
          std::to_string(grid.component_cells(grid.component(c)).size()) +
          " free cells has none; the map has " + std::to_string(grid.count_components()) +
          " separate regions)");
}

PickupDeliveryStream::PickupDeliveryStream(const Grid& grid, std::vector<Cell> pickups,
                                           std::vector<Cell> deliveries, uint64_t seed)
    : grid_(grid), pickups_(std::move(pickups)), deliveries_(std::move(deliveries)), seed_(seed) {
  check_mapd_cells(grid, pickups_, deliveries_);
  pickups_by_component_.resize(grid.count_components());
  deliveries_by_component_.resize(grid.count_components());
  for (Cell c : pickups_) pickups_by_component_[grid.component(c)].push_back(c);
  for (Cell c : deliveries_) deliveries_by_component_[grid.component(c)].push_back(c);
}

Cell PickupDeliveryStream::next_goal(int agent, Cell current) {
  require_free(grid_, agent, current, "MAPD");
  grow_rngs(rngs_, agent, seed_, 0x4d415044ULL);
  if (static_cast<int>(next_is_delivery_.size()) <= agent) next_is_delivery_.resize(agent + 1, 0);
  const bool delivery = next_is_delivery_[agent];
  const int comp = grid_.component(current);
  const std::vector<Cell>& set = (delivery ? deliveries_by_component_ : pickups_by_component_)[comp];
  // check_mapd_cells guarantees a delivery wherever there is a pickup and vice versa, so this
  // can only happen for an agent's first goal, drawn from its start.
  if (set.empty())
    throw std::invalid_argument(
        "MAPD: agent " + std::to_string(agent) + " at " + grid_.describe(current) +
        " cannot reach any " + (delivery ? "delivery" : "pickup") + " cell (its region of " +
        std::to_string(grid_.component_cells(comp).size()) + " free cells has none; the map has " +
        std::to_string(grid_.count_components()) +
        " separate regions): start agents where tasks can reach them");
  next_is_delivery_[agent] = !delivery;
  return draw_other_than(set, current, rngs_[agent]);
}

std::unique_ptr<TaskStream> PickupDeliveryStream::clone_fresh() const {
  return std::make_unique<PickupDeliveryStream>(grid_, pickups_, deliveries_, seed_);
}

namespace {
// Drops the cells of either set that cannot reach the other set (several components only).
// Leaves the sets alone when that would empty one, so check_mapd_cells names a cell instead.
void drop_unreachable(const Grid& grid, MapdCells& out) {
  if (grid.count_components() == 1) return;
  std::vector<char> has_pickup(grid.count_components(), 0), has_delivery(grid.count_components(), 0);
  for (Cell c : out.pickups) has_pickup[grid.component(c)] = 1;
  for (Cell c : out.deliveries) has_delivery[grid.component(c)] = 1;
  std::vector<Cell> p, d;
  for (Cell c : out.pickups) if (has_delivery[grid.component(c)]) p.push_back(c);
  for (Cell c : out.deliveries) if (has_pickup[grid.component(c)]) d.push_back(c);
  if (p.empty() || d.empty()) return;
  const size_t dropped = out.pickups.size() - p.size() + out.deliveries.size() - d.size();
  if (dropped == 0) return;
  out.rule += "; " + std::to_string(dropped) +
              " cells dropped that cannot reach a cell of the other set";
  out.pickups = std::move(p);
  out.deliveries = std::move(d);
}
}  // namespace

MapdCells default_mapd_cells(const Grid& grid) {
  MapdCells out;
  if (!grid.endpoints().empty() && !grid.homes().empty()) {
    out.pickups = grid.endpoints();
    out.deliveries = grid.homes();
    out.rule = "kiva: pickups = endpoints 'e', deliveries = homes 'r'";
    drop_unreachable(grid, out);
    return out;
  }
  int min_x = grid.width(), max_x = -1;
  for (Cell c : grid.free_cells()) {
    min_x = std::min(min_x, grid.x_of(c));
    max_x = std::max(max_x, grid.x_of(c));
  }
  for (Cell c : grid.free_cells()) {
    const int x = grid.x_of(c), y = grid.y_of(c);
    if (x == min_x || x == max_x) {
      out.deliveries.push_back(c);
      continue;
    }
    bool by_obstacle = false;
    static const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
    for (int d = 0; d < 4; ++d) {
      const int nx = x + dx[d], ny = y + dy[d];
      if (grid.in_bounds(nx, ny) && !grid.is_free(grid.cell(nx, ny))) by_obstacle = true;
    }
    if (by_obstacle) out.pickups.push_back(c);
  }
  out.rule = "deliveries = free cells of the leftmost and rightmost free columns; pickups = other "
             "free cells beside an interior obstacle";
  if (out.pickups.empty()) {
    out.pickups = grid.free_cells();
    out.rule += " (no such cell: pickups = all free cells)";
  }
  if (out.deliveries.empty()) out.deliveries = grid.free_cells();
  drop_unreachable(grid, out);
  return out;
}

MapdCells mapd_cells_for_map(const Grid& grid, const std::string& map_path) {
  std::string base = map_path;
  if (base.size() > 4 && base.compare(base.size() - 4, 4, ".map") == 0) base.resize(base.size() - 4);
  if (std::ifstream(base + ".pickups") && std::ifstream(base + ".deliveries")) {
    MapdCells out;
    out.pickups = load_cell_list(grid, base + ".pickups");
    out.deliveries = load_cell_list(grid, base + ".deliveries");
    out.rule = "side files " + base + ".pickups / .deliveries";
    return out;
  }
  return default_mapd_cells(grid);
}

std::vector<Cell> load_cell_list(const Grid& grid, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapError(path + ": cannot open cell list");
  return parse_cell_list(grid, in, path);
}

std::vector<Cell> parse_cell_list(const Grid& grid, std::istream& in, const std::string& name) {
  std::vector<Cell> cells;
  std::string line;
  for (int lineno = 1; std::getline(in, line); ++lineno) {
    if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::replace(line.begin(), line.end(), ',', ' ');
    const auto where = [&] { return name + ":" + std::to_string(lineno) + ": "; };
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream ls(line);
    long long x, y;
    std::string rest;
    if (!(ls >> x) || !(ls >> y) || (ls >> rest))
      throw MapError(where() + "expected 'x y', got '" + quote_input(line) + "'");
    if (x < 0 || y < 0 || x >= grid.width() || y >= grid.height())
      throw MapError(where() + "cell (" + std::to_string(x) + "," + std::to_string(y) +
                     ") is off the map (" + std::to_string(grid.width()) + " x " +
                     std::to_string(grid.height()) + ")");
    const Cell c = grid.cell(static_cast<int>(x), static_cast<int>(y));
    if (!grid.is_free(c))
      throw MapError(where() + "cell (" + std::to_string(x) + "," + std::to_string(y) +
                     ") is an obstacle");
    cells.push_back(c);
  }
  if (in.bad()) throw MapError(name + ": read error");
  if (cells.empty()) throw MapError(name + ": no cells listed");
  return cells;
}

std::vector<Cell> random_starts(const Grid& grid, int count, uint64_t seed) {
  if (count < 1) throw std::invalid_argument("agent count must be at least 1, got " + std::to_string(count));
  if (static_cast<size_t>(count) > grid.free_cells().size())
    throw std::invalid_argument("cannot place " + std::to_string(count) + " agents on " +
                                grid.name() + ": it has only " +
                                std::to_string(grid.free_cells().size()) + " free cells");
  std::vector<Cell> cells = grid.free_cells();
  std::mt19937_64 rng(mix_seed(seed, 0x5354415254ULL));
  // Partial Fisher-Yates: the first `count` cells are a uniform sample without replacement.
  for (int i = 0; i < count; ++i) {
    size_t j = std::uniform_int_distribution<size_t>(i, cells.size() - 1)(rng);
    std::swap(cells[i], cells[j]);
  }
  cells.resize(count);
  return cells;
}

}  // namespace gdrhcr
