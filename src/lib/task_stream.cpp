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
  return draw_other_than(grid_.free_cells(), current, rng(agent));
}

std::unique_ptr<TaskStream> RandomNavigationStream::clone_fresh() const {
  return std::make_unique<RandomNavigationStream>(grid_, seed_);
}

PickupDeliveryStream::PickupDeliveryStream(const Grid& grid, std::vector<Cell> pickups,
                                           std::vector<Cell> deliveries, uint64_t seed)
    : grid_(grid), pickups_(std::move(pickups)), deliveries_(std::move(deliveries)), seed_(seed) {
  if (pickups_.empty() || deliveries_.empty())
    throw std::invalid_argument("MAPD task stream needs at least one pickup and one delivery cell");
  for (auto* set : {&pickups_, &deliveries_})
    for (Cell c : *set)
      if (!grid.is_free(c))
        throw std::invalid_argument("MAPD cell " + grid.describe(c) + " is not a free cell");
}

Cell PickupDeliveryStream::next_goal(int agent, Cell current) {
  grow_rngs(rngs_, agent, seed_, 0x4d415044ULL);
  if (static_cast<int>(next_is_delivery_.size()) <= agent) next_is_delivery_.resize(agent + 1, 0);
  const bool delivery = next_is_delivery_[agent];
  next_is_delivery_[agent] = !delivery;
  return draw_other_than(delivery ? deliveries_ : pickups_, current, rngs_[agent]);
}

std::unique_ptr<TaskStream> PickupDeliveryStream::clone_fresh() const {
  return std::make_unique<PickupDeliveryStream>(grid_, pickups_, deliveries_, seed_);
}

MapdCells default_mapd_cells(const Grid& grid) {
  MapdCells out;
  if (!grid.endpoints().empty() && !grid.homes().empty()) {
    out.pickups = grid.endpoints();
    out.deliveries = grid.homes();
    out.rule = "kiva: pickups = endpoints 'e', deliveries = homes 'r'";
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
  std::ifstream in(path);
  if (!in) throw MapError(path + ": cannot open cell list");
  std::vector<Cell> cells;
  std::string line;
  for (int lineno = 1; std::getline(in, line); ++lineno) {
    if (auto hash = line.find('#'); hash != std::string::npos) line.resize(hash);
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ls(line);
    int x, y;
    std::string rest;
    if (!(ls >> x)) {
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      throw MapError(path + ":" + std::to_string(lineno) + ": expected 'x y', got '" + line + "'");
    }
    if (!(ls >> y) || (ls >> rest))
      throw MapError(path + ":" + std::to_string(lineno) + ": expected 'x y', got '" + line + "'");
    if (!grid.in_bounds(x, y))
      throw MapError(path + ":" + std::to_string(lineno) + ": cell (" + std::to_string(x) + "," +
                     std::to_string(y) + ") is off the map");
    if (!grid.is_free(grid.cell(x, y)))
      throw MapError(path + ":" + std::to_string(lineno) + ": cell (" + std::to_string(x) + "," +
                     std::to_string(y) + ") is an obstacle");
    cells.push_back(grid.cell(x, y));
  }
  if (cells.empty()) throw MapError(path + ": no cells listed");
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
