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

namespace {
// The map's size from its header: MovingAI lines "type ...", "height H", "width W", "map", or
// one line "rows,cols". Leaves `in` at the first row; `line` counts the lines read.
void read_lorr_map_header(std::istream& in, const std::string& path, int& rows, int& cols, int& line) {
  std::string text;
  auto next = [&](const char* what) {
    if (!std::getline(in, text)) throw LorrError(path + ":" + std::to_string(line + 1) + ": missing " + what);
    ++line;
    return trim(text);
  };
  auto number = [&](const std::string& s, const char* what) {
    long v;
    if (!parse_count(trim(s), v) || v < 1 || v > Grid::kMaxCells)
      throw LorrError(path + ":" + std::to_string(line) + ": " + what + " must be a positive integer, got " +
                      quote_input(s));
    return static_cast<int>(v);
  };
  const std::string first = next("the header");
  if (!first.empty() && first[0] == 't') {
    for (const char* key : {"height", "width"}) {
      const std::string l = next(key);
      if (l.rfind(key, 0) != 0) throw LorrError(path + ":" + std::to_string(line) + ": expected '" + key + " N'");
      (key[0] == 'h' ? rows : cols) = number(l.substr(std::string(key).size()), key);
    }
    next("the 'map' line");
  } else {
    const auto comma = first.find(',');
    if (comma == std::string::npos)
      throw LorrError(path + ":1: expected a MovingAI header ('type octile') or 'rows,cols', got " + quote_input(first));
    rows = number(first.substr(0, comma), "rows");
    cols = number(first.substr(comma + 1), "cols");
  }
  if (int64_t(rows) * cols > Grid::kMaxCells)
    throw LorrError(path + ": a map of " + std::to_string(rows) + " x " + std::to_string(cols) + " is too large");
}
}  // namespace

Grid load_lorr_map(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw LorrError(path + ": cannot open the map file");
  int rows = 0, cols = 0, line = 0;
  read_lorr_map_header(in, path, rows, cols, line);
  std::vector<std::string> grid_rows(rows);
  std::string text;
  for (int r = 0; r < rows; ++r) {
    if (!std::getline(in, text))
      throw LorrError(path + ":" + std::to_string(line + 1) + ": the map has " + std::to_string(r) + " rows, the header " +
                      std::to_string(rows));
    ++line;
    if (static_cast<int>(text.size()) < cols)
      throw LorrError(path + ":" + std::to_string(line) + ": row " + std::to_string(r) + " has " +
                      std::to_string(text.size()) + " cells, the width is " + std::to_string(cols));
    grid_rows[r].resize(cols);
    for (int c = 0; c < cols; ++c) grid_rows[r][c] = text[c] == '@' || text[c] == 'T' ? '@' : '.';
  }
  try {
    return Grid::from_rows(grid_rows, path);
  } catch (const MapError& e) {
    throw LorrError(path + ": " + e.what());
  }
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
  p.grid = load_lorr_map(p.map_path);
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
// One agent's moves as the output's letters: the Start-Kit's F/R/C/W in rotation (headings
// given), PlanViz's MAPF letters otherwise.
std::string agent_moves(const Grid& grid, const std::vector<Cell>& p, const std::vector<Heading>* h) {
  std::string moves;
  moves.reserve(p.size() * 2);
  for (size_t t = 0; t + 1 < p.size(); ++t) {
    if (t) moves += ',';
    if (!h) {
      moves += move_letter(grid, p[t], p[t + 1]);
      continue;
    }
    const auto a = action_between(grid, Pose{p[t], (*h)[t]}, Pose{p[t + 1], (*h)[t + 1]});
    if (!a) throw std::logic_error("lorr_output: no action takes " + grid.describe(p[t]) + " to " + grid.describe(p[t + 1]));
    moves += action_letter(*a);
  }
  return moves;
}

// One agent's tasks and events, replayed along its path with the simulator's rule; adds to
// `tasks` ([id, row, col]) and returns the events; `finished` and `cost` (timesteps with a task,
// the Start-Kit's solution cost) grow.
nlohmann::json agent_events(const std::vector<Cell>& p, const std::vector<Cell>& g,
                            const std::vector<long>* given_ids, int lookahead, long& next_own_id,
                            std::vector<std::pair<long, Cell>>& tasks, long& finished, long& cost) {
  const int steps = static_cast<int>(p.size()) - 1;
  std::vector<long> ids(g.size());
  std::vector<char> real(g.size(), 0);  // a task: given an id >= 0, or (own ids) other than where it came from
  for (size_t k = 0; k < g.size(); ++k) {
    const Cell from = k == 0 ? p[0] : g[k - 1];
    real[k] = given_ids ? k < given_ids->size() && (*given_ids)[k] >= 0 : g[k] != from;
    ids[k] = !real[k] ? -1 : given_ids ? (*given_ids)[k] : next_own_id++;
    if (real[k]) tasks.emplace_back(ids[k], g[k]);
  }
  nlohmann::json ev = nlohmann::json::array();
  size_t front = 0, known = std::min<size_t>(std::max(1, lookahead), g.size());
  for (size_t k = 0; k < known; ++k)
    if (real[k]) ev.push_back({ids[k], 0, "assigned"});
  for (int t = 1; t <= steps; ++t) {
    cost += front < g.size() && real[front];
    if (front >= g.size() || p[t] != g[front]) continue;
    if (real[front]) ev.push_back({ids[front], t, "finished"}), ++finished;
    ++front;
    if (known < g.size()) {
      if (real[known]) ev.push_back({ids[known], t, "assigned"});
      ++known;
    }
  }
  return ev;
}
}  // namespace

nlohmann::json lorr_output(const Grid& grid, const std::vector<std::vector<Cell>>& paths,
                           const std::vector<std::vector<Cell>>& goals, int lookahead,
                           const std::vector<std::vector<long>>& task_ids,
                           const std::vector<std::vector<Heading>>* headings) {
  const int n = static_cast<int>(paths.size());
  const int steps = n > 0 ? static_cast<int>(paths[0].size()) - 1 : 0;
  nlohmann::json start = nlohmann::json::array(), actual = nlohmann::json::array();
  nlohmann::json events = nlohmann::json::array();
  std::vector<std::pair<long, Cell>> tasks;
  long finished = 0, next_own_id = 0, sum_of_cost = 0, makespan = 0;
  for (int i = 0; i < n; ++i) {
    const auto& p = paths[i];
    if (static_cast<int>(p.size()) != steps + 1) throw std::invalid_argument("lorr_output: paths of different lengths");
    const std::vector<Heading>* h = headings ? &(*headings)[i] : nullptr;
    if (h && h->size() != p.size()) throw std::invalid_argument("lorr_output: headings and paths of different lengths");
    start.push_back({grid.y_of(p[0]), grid.x_of(p[0]), h ? heading_name((*h)[0]) : "N/A"});
    actual.push_back(agent_moves(grid, p, h));
    const std::vector<Cell> none;
    const bool have_ids = i < static_cast<int>(task_ids.size()) && !task_ids[i].empty();
    long cost = 0;
    events.push_back(agent_events(p, i < static_cast<int>(goals.size()) ? goals[i] : none,
                                  have_ids ? &task_ids[i] : nullptr, lookahead, next_own_id, tasks, finished, cost));
    sum_of_cost += cost;
    makespan = std::max(makespan, cost);
  }
  std::sort(tasks.begin(), tasks.end());
  nlohmann::json task_list = nlohmann::json::array();
  for (auto& [id, c] : tasks) task_list.push_back({id, grid.y_of(c), grid.x_of(c)});
  nlohmann::json j;
  j["actionModel"] = headings ? "MAPF_T" : "MAPF";
  j["AllValid"] = "Yes";
  j["teamSize"] = n;
  j["start"] = std::move(start);
  j["numTaskFinished"] = finished;
  j["sumOfCost"] = sum_of_cost;
  j["makespan"] = makespan;
  j["actualPaths"] = actual;
  j["plannerPaths"] = std::move(actual);  // we execute what we plan (a collision aborts the run)
  j["errors"] = nlohmann::json::array();
  j["events"] = std::move(events);
  j["tasks"] = std::move(task_list);
  return j;
}

namespace {
// [row, col, orientation] of a "start" entry: a free cell, and a heading (E/S/W/N) in MAPF_T.
Pose read_start(const Grid& grid, const nlohmann::json& s, bool rotation, const std::string& where) {
  if (!s.is_array() || s.size() < 2 || !s[0].is_number_integer() || !s[1].is_number_integer())
    throw LorrError(where + ": \"start\" entry must be [row, col, orientation], not " + s.dump());
  const int row = s[0].get<int>(), col = s[1].get<int>();
  if (!grid.in_bounds(col, row) || !grid.is_free(grid.cell(col, row)))
    throw LorrError(where + ": start (row " + std::to_string(row) + ", col " + std::to_string(col) +
                    ") is not a free cell of the map");
  Pose pose{grid.cell(col, row), kEast};
  if (!rotation) return pose;
  const std::string o = s.size() > 2 && s[2].is_string() ? s[2].get<std::string>() : "";
  for (Heading h = 0; h < kNumHeadings; ++h)
    if (o == heading_name(h)) pose.heading = h;
  if (o != heading_name(pose.heading)) throw LorrError(where + ": start orientation must be E, S, W or N, not " + s.dump());
  return pose;
}

// One move letter applied to `pose`: PlanViz's MAPF letters, or the Start-Kit's F/R/C/W (T, a
// timed-out step, waits). False for an unknown letter.
bool apply_letter(const Grid& grid, const std::string& m, bool rotation, Pose& pose) {
  if (m == "W" || m == "T") return true;
  if (rotation) {
    const Action a = m == "F" ? Action::kForward : m == "R" ? Action::kClockwise : Action::kCounterClockwise;
    if (m != "F" && m != "R" && m != "C") return false;
    pose = apply_action(grid, pose, a);
    return true;
  }
  int x = grid.x_of(pose.cell), y = grid.y_of(pose.cell);
  if (m == "R") ++x;
  else if (m == "L") --x;
  else if (m == "U") ++y;
  else if (m == "D") --y;
  else return false;
  pose.cell = grid.in_bounds(x, y) && grid.is_free(grid.cell(x, y)) ? grid.cell(x, y) : kNoCell;
  return true;
}
}  // namespace

std::vector<std::vector<Cell>> read_lorr_paths(const Grid& grid, const nlohmann::json& out, const std::string& name,
                                               std::vector<std::vector<Heading>>* headings) {
  auto need = [&](const char* key) -> const nlohmann::json& {
    auto it = out.find(key);
    if (it == out.end()) throw LorrError(name + ": field \"" + key + "\" is missing");
    return *it;
  };
  if (!out.is_object()) throw LorrError(name + ": a LoRR output must be a JSON object");
  const auto& model = need("actionModel");
  if (model != "MAPF" && model != "MAPF_T")
    throw LorrError(name + ": field \"actionModel\" is " + model.dump() + ", expected \"MAPF_T\" or \"MAPF\"");
  const bool rotation = model == "MAPF_T";
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
  if (headings) headings->assign(n, {});
  for (size_t i = 0; i < n; ++i) {
    const std::string where = name + ": agent " + std::to_string(i);
    Pose pose = read_start(grid, start[i], rotation, where);
    paths[i].push_back(pose.cell);
    if (headings) (*headings)[i].push_back(pose.heading);
    if (!actual[i].is_string()) throw LorrError(where + ": \"actualPaths\" entry must be a string");
    const std::string moves = actual[i].get<std::string>();
    for (size_t pos = 0, t = 0; pos < moves.size(); ++t) {
      const size_t end = std::min(moves.find(',', pos), moves.size());
      const std::string m = trim(moves.substr(pos, end - pos));
      pos = end + 1;
      const Cell from = pose.cell;
      if (!apply_letter(grid, m, rotation, pose))
        throw LorrError(where + ": move " + std::to_string(t) + " is " + quote_input(m) +
                        (rotation ? " (expected F, R, C, W or T)" : " (expected R, L, U, D, W or T)"));
      if (pose.cell == kNoCell)
        throw LorrError(where + ": move " + std::to_string(t) + " (" + m + ") leaves " + grid.describe(from) +
                        " for an obstacle or off the map");
      paths[i].push_back(pose.cell);
      if (headings) (*headings)[i].push_back(pose.heading);
    }
  }
  return paths;
}

}  // namespace gdrhcr
