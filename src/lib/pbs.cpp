// PBS over windowed SIPP: see pbs.hpp. Ma et al., AAAI 2019; RHCR (Li et al., AAAI 2021).
#include "gdrhcr/pbs.hpp"

#include <algorithm>
#include <chrono>
#include <memory>

#include "gdrhcr/sipp.hpp"

namespace gdrhcr {

namespace {
using Clock = std::chrono::steady_clock;

// Finds collisions time step by time step with a stamped cell -> agent table: O(agents * H).
class CollisionScanner {
 public:
  void resize(int cells) {
    if (static_cast<int>(who_.size()) != cells) who_.assign(cells, -1), when_.assign(cells, 0), stamp_ = 0;
  }
  // Calls at(k, t) for each agent's cell. Returns the first collision and counts them all
  // (approximately when three or more agents share a cell: only pairs with the first occupant).
  template <class At>
  PbsCollision scan(int n, int horizon, At at, int* count) {
    PbsCollision first;
    int total = 0;
    for (int t = 0; t <= horizon; ++t) {
      if (++stamp_ == 0) std::fill(when_.begin(), when_.end(), 0), stamp_ = 1;
      for (int k = 0; k < n; ++k) {
        const Cell c = at(k, t);
        if (when_[c] == stamp_) {
          if (first.t < 0) first = {t, who_[c], k, false};
          ++total;
          if (!count) return first;
        } else {
          when_[c] = stamp_;
          who_[c] = k;
        }
      }
      if (t == horizon) break;
      for (int k = 0; k < n; ++k) {
        const Cell u = at(k, t), v = at(k, t + 1);
        if (u == v || when_[v] != stamp_) continue;
        const int o = who_[v];
        if (o == k || at(o, t + 1) != u) continue;
        if (k < o) {
          if (first.t < 0) first = {t, k, o, true};
          ++total;
          if (!count) return first;
        }
      }
    }
    if (count) *count = total;
    return first;
  }

 private:
  std::vector<int> who_;
  std::vector<uint32_t> when_;
  uint32_t stamp_ = 0;
};

// Per-thread scratch, reused across calls on the same grid and horizon.
struct Workspace {
  const Grid* grid = nullptr;
  int cells = -1, horizon = -1;
  std::unique_ptr<Sipp> sipp;
  std::unique_ptr<ConstraintTable> table;
  CollisionScanner scanner;
};

Workspace& workspace(const Grid& grid, int horizon) {
  thread_local Workspace ws;
  if (ws.grid != &grid || ws.cells != grid.num_cells() || ws.horizon != horizon) {
    ws.sipp = std::make_unique<Sipp>(grid);
    ws.table = std::make_unique<ConstraintTable>(grid, horizon);
    ws.grid = &grid;
    ws.cells = grid.num_cells();
    ws.horizon = horizon;
  }
  ws.scanner.resize(grid.num_cells());
  return ws;
}

class PbsSearch {
 public:
  PbsSearch(const Grid& grid, const DistTable& dist, const std::vector<Cell>& starts,
            const std::vector<std::vector<Cell>>& goals, const SoftConstraintTable* soft,
            const PbsConfig& cfg, Workspace& ws, Clock::time_point deadline)
      : grid_(grid), soft_(soft), cfg_(cfg), ws_(ws), deadline_(deadline), n_(static_cast<int>(starts.size())),
        dist_rotation_(dist.action_model() == ActionModel::kRotation) {
    static const std::vector<Cell> kNone;
    agents_.reserve(n_);
    for (int k = 0; k < n_; ++k)
      agents_.emplace_back(dist, starts[k], k < static_cast<int>(goals.size()) ? goals[k] : kNone, cfg.horizon,
                           cfg.start_headings ? (*cfg.start_headings)[k] : kEast);
    cur_.assign(n_, -1);
    lower_.assign(n_, {});
    higher_.assign(n_, {});
    mark_.assign(n_, 0);
    indeg_.assign(n_, 0);
  }

  void run(PbsResult& out);

 private:
  struct Node {
    int parent;
    int hi, lo;                              // the order added by this node (-1 at the root)
    std::vector<std::pair<int, int>> changed;  // (agent, path id) replanned in this node
    int collisions;
    double cost;
    int depth;
  };

  bool out_of_limits() {
    if (cfg_.node_budget > 0 && static_cast<long>(nodes_.size()) >= cfg_.node_budget) return true;
    return Clock::now() > deadline_;
  }
  const std::vector<Cell>& path(int k) const { return store_[cur_[k]]; }
  Cell at(int k, int t) const {
    const auto& p = store_[cur_[k]];
    return p[std::min<size_t>(t, p.size() - 1)];
  }
  PbsCollision scan(int* count) {
    return ws_.scanner.scan(n_, cfg_.horizon, [this](int k, int t) { return at(k, t); }, count);
  }
  int plan(int k);  // SIPP for agent k against its ancestors (the table is filled); path id or -1
  void fill_table(int k);
  void block_cells(ConstraintTable& table) const {
    if (!cfg_.blocked_cells) return;
    for (Cell c : *cfg_.blocked_cells)
      for (int t = 0; t <= table.horizon(); ++t) table.block_vertex(c, t);
  }
  bool reaches(int from, int target);  // target is below `from` (or is it)
  void add_order(int hi, int lo) { lower_[hi].push_back(lo), higher_[lo].push_back(hi); }
  void remove_order(int hi, int lo) { lower_[hi].pop_back(), higher_[lo].pop_back(); }
  void activate(int node);
  bool generate_child(int parent, int hi, int lo);
  double total_cost() const;
  int relevant_depth(int node, const PbsCollision& c);

  const Grid& grid_;
  const SoftConstraintTable* soft_;
  const PbsConfig& cfg_;
  Workspace& ws_;
  Clock::time_point deadline_;
  int n_;
  bool dist_rotation_;
  std::vector<SippAgent> agents_;
  bool cut_short_ = false;
  long sipp_calls_ = 0;

  std::vector<std::vector<Cell>> store_;  // every path planned, by id
  std::vector<std::vector<Heading>> store_headings_;  // its headings (rotation; else empty)
  std::vector<double> store_cost_;
  std::vector<int> store_soft_;
  std::vector<Node> nodes_;
  int active_ = -1;
  std::vector<int> root_paths_;
  std::vector<int> cur_;                        // path id per agent in the active node
  std::vector<std::vector<int>> lower_, higher_;  // the active node's priority DAG
  std::vector<uint32_t> mark_;
  uint32_t mark_stamp_ = 0;
  std::vector<int> indeg_, queue_, order_;
};

void PbsSearch::fill_table(int k) {
  // All (transitive) ancestors of k are hard constraints.
  ConstraintTable& table = *ws_.table;
  table.clear();
  block_cells(table);
  ++mark_stamp_;
  queue_.assign(higher_[k].begin(), higher_[k].end());
  for (int a : queue_) mark_[a] = mark_stamp_;
  for (size_t i = 0; i < queue_.size(); ++i) {
    const int a = queue_[i];
    table.add_path(path(a));
    for (int b : higher_[a])
      if (mark_[b] != mark_stamp_) mark_[b] = mark_stamp_, queue_.push_back(b);
  }
}

int PbsSearch::plan(int k) {
  SippLimits limits;
  limits.deadline = deadline_;
  ++sipp_calls_;
  SippResult r = ws_.sipp->plan(agents_[k], *ws_.table, soft_, cfg_.c_soft, limits);
  if (!r.found) {
    if (r.cut_short) cut_short_ = true;
    return -1;
  }
  store_.push_back(std::move(r.path));
  store_headings_.push_back(std::move(r.headings));
  store_cost_.push_back(r.cost);
  store_soft_.push_back(r.soft_conflicts);
  return static_cast<int>(store_.size()) - 1;
}

bool PbsSearch::reaches(int from, int target) {
  ++mark_stamp_;
  queue_.assign(1, from);
  mark_[from] = mark_stamp_;
  for (size_t i = 0; i < queue_.size(); ++i) {
    if (queue_[i] == target) return true;
    for (int b : lower_[queue_[i]])
      if (mark_[b] != mark_stamp_) mark_[b] = mark_stamp_, queue_.push_back(b);
  }
  return false;
}

void PbsSearch::activate(int node) {
  if (node == active_) return;
  if (active_ >= 0 && nodes_[node].parent == active_) {
    // The usual depth-first step: apply one child's changes on top of its parent.
    for (auto& [k, id] : nodes_[node].changed) cur_[k] = id;
    add_order(nodes_[node].hi, nodes_[node].lo);
    active_ = node;
    return;
  }
  // Backtracking: rebuild from the root along the chain.
  std::vector<int> chain;
  for (int x = node; x >= 0; x = nodes_[x].parent) chain.push_back(x);
  cur_ = root_paths_;
  for (int k = 0; k < n_; ++k) lower_[k].clear(), higher_[k].clear();
  for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
    const Node& x = nodes_[*it];
    for (auto& [k, id] : x.changed) cur_[k] = id;
    if (x.hi >= 0) add_order(x.hi, x.lo);
  }
  active_ = node;
}

double PbsSearch::total_cost() const {
  double c = 0;
  for (int k = 0; k < n_; ++k) c += store_cost_[cur_[k]];
  return c;
}

bool PbsSearch::generate_child(int parent, int hi, int lo) {
  if (reaches(lo, hi)) return false;  // hi is already below lo: the order would be cyclic
  // queue_ now holds lo and everything below it: the agents that may need replanning.
  std::vector<int> affected = queue_;
  add_order(hi, lo);
  // Topological order of the affected agents (Kahn, counting in-edges from affected agents).
  ++mark_stamp_;
  for (int a : affected) mark_[a] = mark_stamp_, indeg_[a] = 0;
  for (int a : affected)
    for (int b : lower_[a])
      if (mark_[b] == mark_stamp_) ++indeg_[b];
  order_.clear();
  for (int a : affected)
    if (indeg_[a] == 0) order_.push_back(a);
  for (size_t i = 0; i < order_.size(); ++i)
    for (int b : lower_[order_[i]])
      if (mark_[b] == mark_stamp_ && --indeg_[b] == 0) order_.push_back(b);
  std::vector<int> topo = order_;

  Node child{parent, hi, lo, {}, 0, 0, nodes_[parent].depth + 1};
  std::vector<std::pair<int, int>> undo;  // (agent, previous path id)
  bool ok = true;
  for (int k : topo) {
    fill_table(k);
    if (k != lo && !ws_.table->violated_by(path(k))) continue;
    const int id = plan(k);
    if (id < 0) { ok = false; break; }
    undo.emplace_back(k, cur_[k]);
    cur_[k] = id;
    child.changed.emplace_back(k, id);
  }
  if (ok) {
    scan(&child.collisions);
    child.cost = total_cost();
  }
  for (auto it = undo.rbegin(); it != undo.rend(); ++it) cur_[it->first] = it->second;
  remove_order(hi, lo);
  if (!ok) return false;
  nodes_.push_back(std::move(child));
  return true;
}

// The depth of the deepest decision on the active node's chain that added an order onto, or
// replanned, one of a, b or their ancestors: the latest decision the dead end depends on.
int PbsSearch::relevant_depth(int node, const PbsCollision& c) {
  ++mark_stamp_;
  queue_.assign({c.a, c.b});
  mark_[c.a] = mark_[c.b] = mark_stamp_;
  for (size_t i = 0; i < queue_.size(); ++i)
    for (int h : higher_[queue_[i]])
      if (mark_[h] != mark_stamp_) mark_[h] = mark_stamp_, queue_.push_back(h);
  for (int x = node; x > 0; x = nodes_[x].parent) {
    const Node& d = nodes_[x];
    bool relevant = mark_[d.lo] == mark_stamp_;
    for (auto& [k, id] : d.changed) relevant = relevant || mark_[k] == mark_stamp_;
    if (relevant) return d.depth;
  }
  return 0;
}

void PbsSearch::run(PbsResult& out) {
  // Root: every agent on its own (soft constraints and blocked cells only).
  ws_.table->clear();
  block_cells(*ws_.table);
  for (int k = 0; k < n_; ++k) {
    const int id = plan(k);
    if (id < 0) {
      out.timed_out = cut_short_;
      return;
    }
    cur_[k] = id;
  }
  root_paths_ = cur_;
  nodes_.push_back({-1, -1, -1, {}, 0, total_cost(), 0});
  active_ = 0;
  std::vector<int> stack = {0};
  while (!stack.empty()) {
    const int node = stack.back();
    stack.pop_back();
    activate(node);
    const PbsCollision c = scan(nullptr);
    if (c.t < 0) {
      out.success = true;
      out.paths.resize(n_);
      for (int k = 0; k < n_; ++k) {
        out.paths[k] = path(k);
        out.soft_conflicts += store_soft_[cur_[k]];
      }
      if (dist_rotation_) {
        out.headings.resize(n_);
        for (int k = 0; k < n_; ++k) out.headings[k] = store_headings_[cur_[k]];
      }
      break;
    }
    if (out_of_limits() || cut_short_) {
      out.timed_out = true;
      break;
    }
    const int before = static_cast<int>(nodes_.size());
    generate_child(node, c.a, c.b);
    if (out_of_limits() || cut_short_) {
      out.timed_out = true;
      break;
    }
    generate_child(node, c.b, c.a);
    if (cut_short_) {
      out.timed_out = true;
      break;
    }
    // Depth first; of two children the one with fewer collisions (then lower cost) goes first.
    const int made = static_cast<int>(nodes_.size()) - before;
    if (made == 2) {
      const Node& x = nodes_[before];
      const Node& y = nodes_[before + 1];
      const bool x_first = x.collisions != y.collisions ? x.collisions < y.collisions : x.cost <= y.cost;
      stack.push_back(x_first ? before + 1 : before);
      stack.push_back(x_first ? before : before + 1);
    } else if (made == 1) {
      stack.push_back(before);
    } else if (cfg_.backjump) {
      const int keep = relevant_depth(node, c);
      while (!stack.empty() && nodes_[stack.back()].depth > keep) stack.pop_back();
    }
  }
  out.nodes = static_cast<long>(nodes_.size());
  out.sipp_calls = sipp_calls_;
}
}  // namespace

PbsResult solve_pbs(const Grid& grid, const DistTable& dist, const std::vector<Cell>& starts,
                    const std::vector<std::vector<Cell>>& goals, const SoftConstraintTable* soft,
                    const PbsConfig& config) {
  const auto t0 = Clock::now();
  PbsResult out;
  if (config.horizon < 1) throw std::invalid_argument("PBS: horizon must be >= 1");
  Workspace& ws = workspace(grid, config.horizon);
  const auto deadline = t0 + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(std::max(0.0, config.time_limit_s)));
  {
    PbsSearch search(grid, dist, starts, goals, soft, config, ws, deadline);
    search.run(out);
  }
  out.time_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return out;
}

PbsCollision first_collision(const Grid& grid, const std::vector<std::vector<Cell>>& paths, int horizon) {
  CollisionScanner scanner;
  scanner.resize(grid.num_cells());
  return scanner.scan(static_cast<int>(paths.size()), horizon,
                      [&](int k, int t) { return paths[k][std::min<size_t>(t, paths[k].size() - 1)]; },
                      nullptr);
}

}  // namespace gdrhcr
