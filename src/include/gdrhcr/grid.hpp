// Grid maps for (lifelong) multi-agent path finding on 4-connected grids.
//
// Formats:
//  - MovingAI benchmark maps (Sturtevant, "Benchmarks for Grid-Based Pathfinding", 2012;
//    Stern et al., "Multi-Agent Pathfinding: Definitions, Variants, and Benchmarks", SoCS 2019).
//  - RHCR's kiva.map (Li et al., "Lifelong Multi-Agent Path Finding in Large-Scale Warehouses",
//    AAAI 2021): header "rows,cols", endpoint count, agent count, max time, then the rows.
//
// Cells are numbered row-major: id = y * width + x, with y growing downwards as in the files.
// The data is flat: per-cell vectors, and a 4-slot neighbour table per cell.
#pragma once

#include <array>
#include <cstdint>
#include <istream>
#include <stdexcept>
#include <string>
#include <vector>

namespace gdrhcr {

using Cell = int32_t;
constexpr Cell kNoCell = -1;

// Thrown for every malformed or unusable map; the message names the file and line.
class MapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a free cell is for. RHCR's kiva format marks endpoints (`e`, shelf access points) and
// homes (`r`, robot start/workstation cells); MovingAI maps only have Travel.
enum class CellKind : uint8_t { Obstacle, Travel, Endpoint, Home };

// Text from an input file made safe to quote in an error message: non-printable bytes become
// \xNN escapes and anything past `max_chars` is cut off with "...".
std::string quote_input(const std::string& text, size_t max_chars = 60);

class Grid {
 public:
  // Largest map accepted, in cells (width * height): 2^24, e.g. 4096 x 4096. Bigger headers
  // are rejected with a MapError before anything is allocated for them.
  static constexpr int64_t kMaxCells = int64_t(1) << 24;

  // Reads a map file, choosing the format by its first line. Throws MapError.
  static Grid load(const std::string& path);
  // The same on a stream: "type ..." first line = MovingAI, "rows,cols" = kiva.
  static Grid parse(std::istream& in, const std::string& name);
  static Grid parse_movingai(std::istream& in, const std::string& name);
  static Grid parse_kiva(std::istream& in, const std::string& name);
  // Rows of characters with the MovingAI/kiva symbols; convenient for tests and generators.
  static Grid from_rows(const std::vector<std::string>& rows, const std::string& name = "inline");

  int width() const { return width_; }
  int height() const { return height_; }
  int num_cells() const { return width_ * height_; }
  const std::string& name() const { return name_; }

  Cell cell(int x, int y) const { return y * width_ + x; }
  int x_of(Cell c) const { return c % width_; }
  int y_of(Cell c) const { return c / width_; }
  bool in_bounds(int x, int y) const { return x >= 0 && y >= 0 && x < width_ && y < height_; }
  bool valid_cell(Cell c) const { return c >= 0 && c < num_cells(); }
  bool is_free(Cell c) const { return valid_cell(c) && kind_[c] != CellKind::Obstacle; }
  CellKind kind(Cell c) const { return kind_[c]; }

  // Free 4-neighbours of c (c itself excluded), at most four.
  struct Neighbours {
    const Cell* b;
    const Cell* e;
    const Cell* begin() const { return b; }
    const Cell* end() const { return e; }
    int size() const { return static_cast<int>(e - b); }
  };
  Neighbours neighbours(Cell c) const {
    const Cell* p = &adjacency_[static_cast<size_t>(c) * 4];
    return {p, p + degree_[c]};
  }
  // True when a single timestep may take an agent from a to b (wait or 4-neighbour move).
  bool step_allowed(Cell a, Cell b) const;

  const std::vector<Cell>& free_cells() const { return free_cells_; }
  const std::vector<Cell>& endpoints() const { return endpoints_; }
  const std::vector<Cell>& homes() const { return homes_; }
  // Number of 4-connected components of the free cells.
  int count_components() const { return static_cast<int>(component_cells_.size()); }
  // The 4-connected component of free cell c (0 .. count_components()-1; -1 for an obstacle),
  // and the free cells of a component in increasing cell order (for a connected map, the same
  // list as free_cells()).
  int component(Cell c) const { return valid_cell(c) ? component_[c] : -1; }
  const std::vector<Cell>& component_cells(int id) const { return component_cells_[id]; }
  std::string describe(Cell c) const;  // "(x,y)"

 private:
  void finish();  // builds adjacency and the cell lists; throws if no cell is free

  int width_ = 0;
  int height_ = 0;
  std::string name_;
  std::vector<CellKind> kind_;
  std::vector<Cell> adjacency_;  // 4 slots per cell
  std::vector<uint8_t> degree_;
  std::vector<Cell> free_cells_, endpoints_, homes_;
  std::vector<int32_t> component_;                // per cell, -1 for obstacles
  std::vector<std::vector<Cell>> component_cells_;
};

}  // namespace gdrhcr
