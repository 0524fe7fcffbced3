#include "gdrhcr/lorr_io.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace gdrhcr {

namespace {

std::string dir_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

std::string resolve(const std::string& base_dir, const std::string& p) {
  return !p.empty() && p[0] == '/' ? p : base_dir + p;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

// A whole-line non-negative integer, or false.
bool parse_count(const std::string& s, long& out) {
  if (s.empty() || s.size() > 12) return false;
  for (char ch : s)
    if (ch < '0' || ch > '9') return false;
  out = std::stol(s);
  return true;
}

const nlohmann::json& field(const nlohmann::json& j, const std::string& name, const std::string& file) {
  auto it = j.find(name);
  if (it == j.end()) throw LorrError(file + ": field \"" + name + "\" is missing");
  return *it;
}

std::string string_field(const nlohmann::json& j, const std::string& name, const std::string& file) {
  const auto& v = field(j, name, file);
  if (!v.is_string() || v.get<std::string>().empty())
    throw LorrError(file + ": field \"" + name + "\" must be a non-empty string, not " + v.dump());
  return v.get<std::string>();
}

int int_field(const nlohmann::json& j, const std::string& name, const std::string& file, int min, int max) {
  const auto& v = field(j, name, file);
  if (!v.is_number_integer() || v.get<long long>() < min || v.get<long long>() > max)
    throw LorrError(file + ": field \"" + name + "\" must be an integer in [" + std::to_string(min) + ", " +
                    std::to_string(max) + "], not " + v.dump());
  return static_cast<int>(v.get<long long>());
}

}  // namespace

std::vector<Cell> load_lorr_cells(const Grid& grid, const std::string& path, const std::string& what) {
  std::ifstream in(path);
  if (!in) throw LorrError(path + ": cannot open " + what + " file");
  std::vector<Cell> cells;
  long count = -1;
  int count_line = 0;
  std::string line;
  for (int lineno = 1; std::getline(in, line); ++lineno) {
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    long v;
    if (!parse_count(t, v))
      throw LorrError(path + ":" + std::to_string(lineno) + ": expected one non-negative integer (" +
                      (count < 0 ? "the number of " + what + "s" : "a linear cell id row*width+col") +
                      "), got " + quote_input(t));
    if (count < 0) {
      count = v;
      count_line = lineno;
      if (count > grid.num_cells() && what == "agent")
        throw LorrError(path + ":" + std::to_string(lineno) + ": " + std::to_string(count) +
                        " agents do not fit on a map of " + std::to_string(grid.num_cells()) + " cells");
      continue;
    }
    if (static_cast<long>(cells.size()) >= count)
      throw LorrError(path + ":" + std::to_string(lineno) + ": more " + what + "s than the " +
                      std::to_string(count) + " announced on line " + std::to_string(count_line));
    if (v >= grid.num_cells())
      throw LorrError(path + ":" + std::to_string(lineno) + ": cell id " + std::to_string(v) +
                      " is off the map (" + std::to_string(grid.width()) + " x " + std::to_string(grid.height()) +
                      " has ids 0.." + std::to_string(grid.num_cells() - 1) + ")");
    const Cell c = static_cast<Cell>(v);
    if (!grid.is_free(c))
      throw LorrError(path + ":" + std::to_string(lineno) + ": cell id " + std::to_string(v) + " " +
                      grid.describe(c) + " is an obstacle");
    cells.push_back(c);
  }
  if (count < 0) throw LorrError(path + ": empty " + what + " file (expected a count line)");
  if (static_cast<long>(cells.size()) < count)
    throw LorrError(path + ":" + std::to_string(count_line) + ": announces " + std::to_string(count) + " " + what +
                    "s but the file lists " + std::to_string(cells.size()));
  return cells;
}

LorrProblem load_lorr_problem(const std::string& problem_path) {
  std::ifstream in(problem_path);
  if (!in) throw LorrError(problem_path + ": cannot open the LoRR problem file");
  std::stringstream buf;
  buf << in.rdbuf();
  const std::string text = buf.str();
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // Name the line: count newlines before the byte the parser stopped at.
    const size_t at = std::min<size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    const long line = 1 + std::count(text.begin(), text.begin() + at, '\n');
    throw LorrError(problem_path + ":" + std::to_string(line) + ": not valid JSON (" + e.what() + ")");
  }
  if (!j.is_object()) throw LorrError(problem_path + ":1: the LoRR problem must be a JSON object");
  LorrProblem p;
  p.problem_path = problem_path;
  const std::string dir = dir_of(problem_path);
  p.map_path = resolve(dir, string_field(j, "mapFile", problem_path));
  p.agent_path = resolve(dir, string_field(j, "agentFile", problem_path));
  p.task_path = resolve(dir, string_field(j, "taskFile", problem_path));
  p.team_size = int_field(j, "teamSize", problem_path, 1, 10000000);
  if (j.contains("numTasksReveal")) p.num_tasks_reveal = int_field(j, "numTasksReveal", problem_path, 1, 1000);
  if (j.contains("taskAssignmentStrategy")) {
    const std::string s = string_field(j, "taskAssignmentStrategy", problem_path);
    try {
      p.strategy = TaskListStream::parse_strategy(s);
    } catch (const std::invalid_argument& e) {
      throw LorrError(problem_path + ": field \"taskAssignmentStrategy\": " + e.what());
    }
  }
  p.grid = Grid::load(p.map_path);
  std::vector<Cell> agents = load_lorr_cells(p.grid, p.agent_path, "agent");
  if (static_cast<int>(agents.size()) < p.team_size)
    throw LorrError(problem_path + ": field \"teamSize\" is " + std::to_string(p.team_size) + " but " +
                    p.agent_path + " lists only " + std::to_string(agents.size()) + " agents");
  agents.resize(p.team_size);
  std::vector<int> seen(p.grid.num_cells(), -1);
  for (int i = 0; i < p.team_size; ++i) {
    if (seen[agents[i]] >= 0)
      throw LorrError(p.agent_path + ": agents " + std::to_string(seen[agents[i]]) + " and " + std::to_string(i) +
                      " start on the same cell " + std::to_string(agents[i]) + " " + p.grid.describe(agents[i]));
    seen[agents[i]] = i;
  }
  p.starts = std::move(agents);
  p.tasks = load_lorr_cells(p.grid, p.task_path, "task");
  if (p.tasks.empty()) throw LorrError(p.task_path + ": the task file lists no tasks");
  return p;
}

Cell RecordingTaskStream::next_goal(int agent, Cell current) {
  const Cell g = inner_.next_goal(agent, current);
  if (static_cast<int>(goals_.size()) <= agent) goals_.resize(agent + 1);
  goals_[agent].push_back(g);
  return g;
}

namespace {
char move_letter(const Grid& grid, Cell a, Cell b) {
  if (a == b) return 'W';
  const int dx = grid.x_of(b) - grid.x_of(a), dy = grid.y_of(b) - grid.y_of(a);
  if (dx == 1 && dy == 0) return 'R';
  if (dx == -1 && dy == 0) return 'L';
  if (dx == 0 && dy == 1) return 'U';  // row + 1: PlanViz's "U", drawn downwards
  if (dx == 0 && dy == -1) return 'D';
  throw std::logic_error("lorr_output: a path jumps from " + grid.describe(a) + " to " + grid.describe(b));
}
}  // namespace

namespace {
// The first quarter turn from `heading` towards `target` (clockwise for a half turn).
Action turn_towards(Heading heading, Heading target) {
  return ((target - heading) & 3) == 3 ? Action::kCounterClockwise : Action::kClockwise;
}
}  // namespace

std::vector<Action> rotation_actions_for_step(const Grid& grid, const std::vector<Cell>& pos,
                                              const std::vector<Heading>& headings, const std::vector<Cell>& next) {
  const int n = static_cast<int>(pos.size());
  std::vector<Action> act(n, Action::kWait);
  std::vector<int> entering(grid.num_cells(), -1);  // the agent moving into a cell, if any
  std::vector<int> staying;
  for (int i = 0; i < n; ++i) {
    const Heading d = heading_of_move(grid, pos[i], next[i]);
    if (next[i] != pos[i] && d == kNoHeading)
      throw std::logic_error("rotation_actions_for_step: agent " + std::to_string(i) + " jumps from " +
                             grid.describe(pos[i]) + " to " + grid.describe(next[i]));
    if (d != kNoHeading && d == headings[i]) {
      act[i] = Action::kForward;
      entering[next[i]] = i;
    } else {
      if (d != kNoHeading) act[i] = turn_towards(headings[i], d);
      staying.push_back(i);
    }
  }
  while (!staying.empty()) {  // whoever moves into a staying agent's cell stays too
    const int i = staying.back();
    staying.pop_back();
    const int j = entering[pos[i]];
    if (j < 0 || act[j] != Action::kForward) continue;
    act[j] = Action::kWait;  // it faces its next cell already
    staying.push_back(j);
  }
  return act;
}

nlohmann::json lorr_output(const Grid& grid, const std::vector<std::vector<Cell>>& paths,
                           const std::vector<std::vector<Cell>>& goals, int lookahead,
                           const std::vector<std::vector<long>>& task_ids) {
  const int n = static_cast<int>(paths.size());
  const int steps = n > 0 ? static_cast<int>(paths[0].size()) - 1 : 0;
  const int L = std::max(1, lookahead);
  nlohmann::json start = nlohmann::json::array(), actual = nlohmann::json::array();
  nlohmann::json events = nlohmann::json::array(), tasks = nlohmann::json::array();
  long finished = 0, next_own_id = 0;
  for (int i = 0; i < n; ++i) {
    const auto& p = paths[i];
    if (static_cast<int>(p.size()) != steps + 1) throw std::invalid_argument("lorr_output: paths of different lengths");
    start.push_back({grid.y_of(p[0]), grid.x_of(p[0]), "N/A"});
    std::string moves;
    moves.reserve(size_t(steps) * 2);
    for (int t = 0; t < steps; ++t) {
      if (t) moves += ',';
      moves += move_letter(grid, p[t], p[t + 1]);
    }
    actual.push_back(std::move(moves));

    // Replay the simulator's goal queue along the path.
    const std::vector<Cell> none;
    const auto& g = i < static_cast<int>(goals.size()) ? goals[i] : none;
    const bool have_ids = i < static_cast<int>(task_ids.size()) && !task_ids[i].empty();
    std::vector<long> ids(g.size());
    std::vector<char> real(g.size(), 0);  // a task, not a goal equal to the cell it came from
    for (size_t k = 0; k < g.size(); ++k) {
      const Cell from = k == 0 ? p[0] : g[k - 1];
      const long given = have_ids && k < task_ids[i].size() ? task_ids[i][k] : -2;
      real[k] = g[k] != from && given != -1;
      ids[k] = !real[k] ? -1 : given >= 0 ? given : next_own_id++;
      if (real[k] && !have_ids) tasks.push_back({ids[k], grid.y_of(g[k]), grid.x_of(g[k])});
    }
    if (have_ids)
      for (size_t k = 0; k < g.size(); ++k)
        if (real[k]) tasks.push_back({ids[k], grid.y_of(g[k]), grid.x_of(g[k])});
    nlohmann::json ev = nlohmann::json::array();
    size_t front = 0, known = std::min<size_t>(L, g.size());
    for (size_t k = 0; k < known; ++k)
      if (real[k]) ev.push_back({ids[k], 0, "assigned"});
    for (int t = 1; t <= steps && front < g.size(); ++t) {
      if (p[t] != g[front]) continue;
      if (real[front]) ev.push_back({ids[front], t, "finished"}), ++finished;
      ++front;
      if (known < g.size()) {
        if (real[known]) ev.push_back({ids[known], t, "assigned"});
        ++known;
      }
    }
    events.push_back(std::move(ev));
  }
  nlohmann::json j;
  j["actionModel"] = "MAPF";
  j["AllValid"] = "Yes";
  j["teamSize"] = n;
  j["start"] = std::move(start);
  j["numTaskFinished"] = finished;
  j["makespan"] = steps;
  j["actualPaths"] = std::move(actual);
  j["errors"] = nlohmann::json::array();
  j["events"] = std::move(events);
  j["tasks"] = std::move(tasks);
  return j;
}

std::vector<std::vector<Cell>> read_lorr_paths(const Grid& grid, const nlohmann::json& out, const std::string& name) {
  auto need = [&](const char* key) -> const nlohmann::json& {
    auto it = out.find(key);
    if (it == out.end()) throw LorrError(name + ": field \"" + key + "\" is missing");
    return *it;
  };
  if (!out.is_object()) throw LorrError(name + ": a LoRR output must be a JSON object");
  const auto& model = need("actionModel");
  if (model != "MAPF") throw LorrError(name + ": field \"actionModel\" is " + model.dump() + ", only \"MAPF\" is read");
  const auto& team = need("teamSize");
  const auto& start = need("start");
  const auto& actual = need("actualPaths");
  if (!team.is_number_integer() || team.get<long long>() < 0)
    throw LorrError(name + ": field \"teamSize\" must be a non-negative integer");
  const size_t n = team.get<size_t>();
  if (!start.is_array() || start.size() != n) throw LorrError(name + ": field \"start\" must list teamSize entries");
  if (!actual.is_array() || actual.size() != n)
    throw LorrError(name + ": field \"actualPaths\" must list teamSize strings");
  std::vector<std::vector<Cell>> paths(n);
  for (size_t i = 0; i < n; ++i) {
    const auto& s = start[i];
    const std::string where = name + ": agent " + std::to_string(i);
    if (!s.is_array() || s.size() < 2 || !s[0].is_number_integer() || !s[1].is_number_integer())
      throw LorrError(where + ": \"start\" entry must be [row, col, orientation], not " + s.dump());
    const int row = s[0].get<int>(), col = s[1].get<int>();
    if (!grid.in_bounds(col, row) || !grid.is_free(grid.cell(col, row)))
      throw LorrError(where + ": start (row " + std::to_string(row) + ", col " + std::to_string(col) +
                      ") is not a free cell of the map");
    Cell c = grid.cell(col, row);
    paths[i].push_back(c);
    if (!actual[i].is_string()) throw LorrError(where + ": \"actualPaths\" entry must be a string");
    const std::string moves = actual[i].get<std::string>();
    size_t pos = 0;
    for (int t = 0; pos < moves.size(); ++t) {
      size_t end = moves.find(',', pos);
      if (end == std::string::npos) end = moves.size();
      const std::string m = trim(moves.substr(pos, end - pos));
      pos = end + 1;
      int x = grid.x_of(c), y = grid.y_of(c);
      if (m == "R") ++x;
      else if (m == "L") --x;
      else if (m == "U") ++y;
      else if (m == "D") --y;
      else if (m != "W" && m != "T")
        throw LorrError(where + ": move " + std::to_string(t) + " is " + quote_input(m) +
                        " (expected R, L, U, D, W or T)");
      if (!grid.in_bounds(x, y) || !grid.is_free(grid.cell(x, y)))
        throw LorrError(where + ": move " + std::to_string(t) + " (" + m + ") leaves " + grid.describe(c) +
                        " for an obstacle or off the map");
      c = grid.cell(x, y);
      paths[i].push_back(c);
    }
  }
  return paths;
}

}  // namespace gdrhcr
