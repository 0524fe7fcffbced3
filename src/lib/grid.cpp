#include "gdrhcr/grid.hpp"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <queue>
#include <sstream>

namespace gdrhcr {

std::string quote_input(const std::string& text, size_t max_chars) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (i == max_chars) { out += "..."; break; }
    const unsigned char ch = static_cast<unsigned char>(text[i]);
    if (ch >= 0x20 && ch < 0x7f) {
      out += static_cast<char>(ch);
    } else {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[ch >> 4];
      out += hex[ch & 15];
    }
  }
  return out;
}

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

// Header numbers: up to 9 digits (so no overflow); the size check is done on the product.
bool parse_positive(const std::string& s, int& out) {
  if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), ::isdigit)) return false;
  out = std::stoi(s);
  return out > 0;
}

void check_size(const std::string& name, int line, int height, int width) {
  const int64_t cells = int64_t(height) * width;
  if (cells > Grid::kMaxCells)
    fail(name, line, "map of " + std::to_string(width) + " x " + std::to_string(height) + " = " +
                         std::to_string(cells) + " cells is larger than the limit of " +
                         std::to_string(Grid::kMaxCells) + " cells");
}

std::string describe_symbol(char ch) {
  return quote_input(std::string(1, ch));
}

// Reads `height` rows of `width` symbols. Memory grows with the rows actually read, so a header
// that lies about the size cannot make the parser allocate for cells the file does not have.
void read_rows(std::istream& in, const std::string& name, int first_line, int height, int width,
               std::vector<CellKind>& kind) {
  kind.clear();
  std::string line;
  for (int y = 0; y < height; ++y) {
    int lineno = first_line + y;
    if (!std::getline(in, line))
      fail(name, lineno, "truncated map: expected " + std::to_string(height) + " rows, found " +
                             std::to_string(y));
    line = strip(line);
    if (static_cast<int64_t>(line.size()) != width)
      fail(name, lineno, "row " + std::to_string(y) + " has " + std::to_string(line.size()) +
                             " cells, expected width " + std::to_string(width));
    for (int x = 0; x < width; ++x) {
      CellKind k;
      if (!classify(line[x], k))
        fail(name, lineno, "unknown map symbol '" + describe_symbol(line[x]) + "' at column " +
                               std::to_string(x));
      kind.push_back(k);
    }
  }
  for (int lineno = first_line + height; std::getline(in, line); ++lineno)
    if (!strip(line).empty())
      fail(name, lineno, "unexpected text after the last map row: '" + quote_input(strip(line)) + "'");
}

}  // namespace

Grid Grid::load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapError(path + ": cannot open map file");
  return parse(in, path);
}

Grid Grid::parse(std::istream& in, const std::string& name) {
  const auto start = in.tellg();
  std::string first;
  // The first non-empty line tells the format (MovingAI files may start with a blank line).
  while (std::getline(in, first) && strip(first).empty()) {}
  if (strip(first).empty()) fail(name, 0, "empty map file");
  first = strip(first);
  in.clear();
  in.seekg(start);
  if (!in) fail(name, 0, "cannot rewind the map stream");
  if (first.rfind("type", 0) == 0) return parse_movingai(in, name);
  if (first.find(',') != std::string::npos) return parse_kiva(in, name);
  fail(name, 1, "unrecognised map format: expected a MovingAI header 'type octile' or a kiva "
                "header 'rows,cols', got '" + quote_input(first) + "'");
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
    if (key == "map") {
      if (!value.empty()) fail(name, lineno, "unexpected text after 'map': '" + quote_input(line) + "'");
      break;
    }
    if (!extra.empty()) fail(name, lineno, "malformed header line '" + quote_input(line) + "'");
    if (key == "type") {
      if (saw_type) fail(name, lineno, "duplicate 'type' header line");
      saw_type = true;
    } else if (key == "height" || key == "width") {
      int v;
      if (!parse_positive(value, v))
        fail(name, lineno, key + " must be a positive integer, got '" + quote_input(value) + "'");
      int& slot = key == "height" ? height : width;
      if (slot >= 0) fail(name, lineno, "duplicate '" + key + "' header line");
      slot = v;
    } else {
      fail(name, lineno, "unexpected header line '" + quote_input(line) +
                             "' (expected type/height/width/map)");
    }
  }
  if (!saw_type) fail(name, 0, "missing 'type' header line");
  if (height < 0) fail(name, 0, "missing 'height' header line");
  if (width < 0) fail(name, 0, "missing 'width' header line");
  if (in.eof() && line != "map") fail(name, lineno, "missing 'map' line before the rows");
  check_size(name, lineno, height, width);
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
  if (!std::getline(in, line)) fail(name, 1, "empty map file");
  line = strip(line);
  auto comma = line.find(',');
  int height, width;
  if (comma == std::string::npos || !parse_positive(strip(line.substr(0, comma)), height) ||
      !parse_positive(strip(line.substr(comma + 1)), width))
    fail(name, 1, "expected 'rows,cols' with positive integers, got '" + quote_input(line) + "'");
  check_size(name, 1, height, width);
  // Lines 2-4: endpoint count, agent count, max time. Only checked for being numbers: RHCR's
  // own loader reads and ignores them, so a count that disagrees with the rows is tolerated.
  // rows,cols must be right: the row count and every row's width are checked.
  for (int l = 2; l <= 4; ++l) {
    if (!std::getline(in, line)) fail(name, l, "truncated kiva header");
    line = strip(line);
    if (line.empty() || !std::all_of(line.begin(), line.end(), ::isdigit))
      fail(name, l, "expected a number in the kiva header, got '" + quote_input(line) + "'");
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
  check_size(name, 0, g.height_, g.width_);
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
  // 4-connected components, numbered in the order of their lowest cell; scanning the free cells
  // in order keeps every component's cell list sorted.
  component_.assign(n, -1);
  component_cells_.clear();
  std::vector<Cell> stack;
  for (Cell s : free_cells_) {
    if (component_[s] >= 0) continue;
    const int id = static_cast<int>(component_cells_.size());
    component_cells_.emplace_back();
    component_[s] = id;
    stack.push_back(s);
    while (!stack.empty()) {
      const Cell c = stack.back();
      stack.pop_back();
      for (Cell nb : neighbours(c))
        if (component_[nb] < 0) { component_[nb] = id; stack.push_back(nb); }
    }
  }
  for (Cell c : free_cells_) component_cells_[component_[c]].push_back(c);
}

bool Grid::step_allowed(Cell a, Cell b) const {
  if (!is_free(a) || !is_free(b)) return false;
  if (a == b) return true;
  for (Cell n : neighbours(a))
    if (n == b) return true;
  return false;
}

std::string Grid::describe(Cell c) const {
  if (!valid_cell(c)) return "(invalid cell " + std::to_string(c) + ")";
  return "(" + std::to_string(x_of(c)) + "," + std::to_string(y_of(c)) + ")";
}

}  // namespace gdrhcr
