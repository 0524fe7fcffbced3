#include "gdrhcr/grid.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <queue>
#include <sstream>

namespace gdrhcr {
namespace {

std::string strip(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ' || s.back() == '\t')) s.pop_back();
  size_t i = 0;
  while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
  return s.substr(i);
}

[[noreturn]] void fail(const std::string& name, int line, const std::string& what) {
  std::ostringstream os;
  os << name;
  if (line > 0) os << ":" << line;
  os << ": " << what;
  throw MapError(os.str());
}

// MovingAI: '.' and 'G' free; '@', 'T', 'O', 'W' blocked. Other letters appear in benchmark
// sets (S swamp, E emitter in LoRR maps) and are passable there, so they are free here too.
// Kiva: '@' obstacle, 'e' endpoint, 'r' home, '.' travel.
bool classify(char ch, CellKind& kind) {
  switch (ch) {
    case '.': case 'G': kind = CellKind::Travel; return true;
    case '@': case 'T': case 'O': case 'W': kind = CellKind::Obstacle; return true;
    case 'e': kind = CellKind::Endpoint; return true;
    case 'r': kind = CellKind::Home; return true;
    default:
      if (std::isalpha(static_cast<unsigned char>(ch))) { kind = CellKind::Travel; return true; }
      return false;
  }
}

bool parse_positive(const std::string& s, int& out) {
  if (s.empty() || s.size() > 6 || !std::all_of(s.begin(), s.end(), ::isdigit)) return false;
  out = std::stoi(s);
  return out > 0;
}

void read_rows(std::istream& in, const std::string& name, int first_line, int height, int width,
               std::vector<CellKind>& kind) {
  kind.assign(static_cast<size_t>(width) * height, CellKind::Obstacle);
  std::string line;
  for (int y = 0; y < height; ++y) {
    int lineno = first_line + y;
    if (!std::getline(in, line))
      fail(name, lineno, "truncated map: expected " + std::to_string(height) + " rows, found " +
                             std::to_string(y));
    line = strip(line);
    if (static_cast<int>(line.size()) != width)
      fail(name, lineno, "row " + std::to_string(y) + " has " + std::to_string(line.size()) +
                             " cells, expected width " + std::to_string(width));
    for (int x = 0; x < width; ++x) {
      if (!classify(line[x], kind[static_cast<size_t>(y) * width + x]))
        fail(name, lineno, std::string("unknown map symbol '") + line[x] + "' at column " +
                               std::to_string(x));
    }
  }
  for (int lineno = first_line + height; std::getline(in, line); ++lineno)
    if (!strip(line).empty()) fail(name, lineno, "unexpected text after the last map row");
}

}  // namespace

Grid Grid::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw MapError(path + ": cannot open map file");
  std::string first;
  std::getline(in, first);
  first = strip(first);
  in.clear();
  in.seekg(0);
  if (first.rfind("type", 0) == 0) return parse_movingai(in, path);
  if (first.find(',') != std::string::npos) return parse_kiva(in, path);
  fail(path, 1, "unrecognised map format: expected a MovingAI header 'type octile' or a kiva "
                "header 'rows,cols'");
}

Grid Grid::parse_movingai(std::istream& in, const std::string& name) {
  std::string line;
  int lineno = 0, height = -1, width = -1;
  bool saw_type = false;
  while (std::getline(in, line)) {
    ++lineno;
    line = strip(line);
    if (line.empty()) continue;
    std::istringstream ls(line);
    std::string key, value, extra;
    ls >> key >> value >> extra;
    if (key == "map") break;
    if (!extra.empty()) fail(name, lineno, "malformed header line '" + line + "'");
    if (key == "type") {
      saw_type = true;
    } else if (key == "height" || key == "width") {
      int v;
      if (!parse_positive(value, v)) fail(name, lineno, key + " must be a positive integer, got '" + value + "'");
      (key == "height" ? height : width) = v;
    } else {
      fail(name, lineno, "unexpected header line '" + line + "' (expected type/height/width/map)");
    }
  }
  if (!saw_type) fail(name, 0, "missing 'type' header line");
  if (height < 0) fail(name, 0, "missing 'height' header line");
  if (width < 0) fail(name, 0, "missing 'width' header line");
  if (in.eof() && line != "map") fail(name, lineno, "missing 'map' line before the rows");
  Grid g;
  g.width_ = width;
  g.height_ = height;
  g.name_ = name;
  read_rows(in, name, lineno + 1, height, width, g.kind_);
  g.finish();
  return g;
}

Grid Grid::parse_kiva(std::istream& in, const std::string& name) {
  std::string line;
  if (!std::getline(in, line)) fail(name, 1, "empty file");
  line = strip(line);
  auto comma = line.find(',');
  int height, width;
  if (comma == std::string::npos || !parse_positive(strip(line.substr(0, comma)), height) ||
      !parse_positive(strip(line.substr(comma + 1)), width))
    fail(name, 1, "expected 'rows,cols' with positive integers, got '" + line + "'");
  // Lines 2-4: endpoint count, agent count, max time. Only checked for being numbers.
  for (int l = 2; l <= 4; ++l) {
    if (!std::getline(in, line)) fail(name, l, "truncated kiva header");
    line = strip(line);
    if (line.empty() || !std::all_of(line.begin(), line.end(), ::isdigit))
      fail(name, l, "expected a number in the kiva header, got '" + line + "'");
  }
  Grid g;
  g.width_ = width;
  g.height_ = height;
  g.name_ = name;
  read_rows(in, name, 5, height, width, g.kind_);
  g.finish();
  return g;
}

Grid Grid::from_rows(const std::vector<std::string>& rows, const std::string& name) {
  if (rows.empty()) throw MapError(name + ": no rows");
  std::string text;
  for (auto& r : rows) text += r + "\n";
  std::istringstream in(text);
  Grid g;
  g.height_ = static_cast<int>(rows.size());
  g.width_ = static_cast<int>(rows[0].size());
  g.name_ = name;
  if (g.width_ == 0) throw MapError(name + ": empty row");
  read_rows(in, name, 1, g.height_, g.width_, g.kind_);
  g.finish();
  return g;
}

void Grid::finish() {
  const int n = num_cells();
  adjacency_.assign(static_cast<size_t>(n) * 4, kNoCell);
  degree_.assign(n, 0);
  free_cells_.clear();
  static const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
  for (Cell c = 0; c < n; ++c) {
    if (kind_[c] == CellKind::Obstacle) continue;
    free_cells_.push_back(c);
    if (kind_[c] == CellKind::Endpoint) endpoints_.push_back(c);
    if (kind_[c] == CellKind::Home) homes_.push_back(c);
    const int x = x_of(c), y = y_of(c);
    for (int d = 0; d < 4; ++d) {
      const int nx = x + dx[d], ny = y + dy[d];
      if (in_bounds(nx, ny) && kind_[cell(nx, ny)] != CellKind::Obstacle)
        adjacency_[static_cast<size_t>(c) * 4 + degree_[c]++] = cell(nx, ny);
    }
  }
  if (free_cells_.empty()) throw MapError(name_ + ": the map has no free cell");
}

bool Grid::step_allowed(Cell a, Cell b) const {
  if (!is_free(a) || !is_free(b)) return false;
  if (a == b) return true;
  for (Cell n : neighbours(a))
    if (n == b) return true;
  return false;
}

int Grid::count_components() const {
  std::vector<char> seen(num_cells(), 0);
  int components = 0;
  std::vector<Cell> stack;
  for (Cell s : free_cells_) {
    if (seen[s]) continue;
    ++components;
    seen[s] = 1;
    stack.push_back(s);
    while (!stack.empty()) {
      Cell c = stack.back();
      stack.pop_back();
      for (Cell n : neighbours(c))
        if (!seen[n]) { seen[n] = 1; stack.push_back(n); }
    }
  }
  return components;
}

std::string Grid::describe(Cell c) const {
  if (!valid_cell(c)) return "(invalid cell " + std::to_string(c) + ")";
  return "(" + std::to_string(x_of(c)) + "," + std::to_string(y_of(c)) + ")";
}

}  // namespace gdrhcr
