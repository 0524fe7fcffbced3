// The action models an agent moves in (issue 23).
//
//  - kMapf: classic MAPF on a 4-connected grid (Stern et al., "Multi-Agent Pathfinding:
//    Definitions, Variants, and Benchmarks", SoCS 2019): in one timestep an agent waits or moves
//    to any free 4-neighbour. Agents have no heading.
//  - kRotation: the League of Robot Runners' MAPF_T (LoRR Start-Kit v1.1.5, inc/ActionModel.h,
//    inc/States.h): an agent's state is its cell and its heading, east/south/west/north = 0/1/2/3;
//    in one timestep it goes forward one cell in its heading (F), rotates clockwise (R: east ->
//    south), rotates counter-clockwise (C: east -> north) or waits (W). Cells are numbered
//    row-major with y growing downwards, so forward from east is x+1, south y+1, west x-1,
//    north y-1. Vertex and edge conflicts are on cells, as in kMapf. Goals are cells (any
//    heading). The Start-Kit starts every agent facing east.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

enum class ActionModel { kMapf, kRotation };

// "mapf" or "rotation"; throws std::invalid_argument naming a bad value and the choices.
ActionModel parse_action_model(const std::string& text);
const char* action_model_name(ActionModel model);

// An agent's heading in the rotation model (LoRR's orientation).
using Heading = int8_t;
constexpr Heading kEast = 0, kSouth = 1, kWest = 2, kNorth = 3;
constexpr Heading kNoHeading = -1;
constexpr int kNumHeadings = 4;

inline Heading rotate_cw(Heading h) { return static_cast<Heading>((h + 1) & 3); }
inline Heading rotate_ccw(Heading h) { return static_cast<Heading>((h + 3) & 3); }
// Quarter turns from heading a to heading b: 0, 1 or 2.
inline int turn_steps(Heading a, Heading b) {
  const int d = (b - a) & 3;
  return d == 3 ? 1 : d;
}
// "E", "S", "W", "N" (LoRR's letters for a start orientation); "?" for anything else.
const char* heading_name(Heading h);

// The free 4-neighbour that heading h faces from cell c; kNoCell when that is off the map or an
// obstacle.
Cell forward_cell(const Grid& grid, Cell c, Heading h);
// The heading of a move from `from` to the 4-neighbour `to`; kNoHeading when they are not
// 4-neighbours (a wait included).
Heading heading_of_move(const Grid& grid, Cell from, Cell to);

// An agent's state in the rotation model.
struct Pose {
  Cell cell = kNoCell;
  Heading heading = kEast;
  bool operator==(const Pose& o) const { return cell == o.cell && heading == o.heading; }
  bool operator!=(const Pose& o) const { return !(*this == o); }
};

// The Start-Kit's actions, with its letters (src/ActionModel.cpp: F, R, C, W).
enum class Action : char { kForward = 'F', kClockwise = 'R', kCounterClockwise = 'C', kWait = 'W' };
inline char action_letter(Action a) { return static_cast<char>(a); }

// The pose one action leads to. A forward off the map or into an obstacle gives cell kNoCell.
Pose apply_action(const Grid& grid, Pose p, Action a);
// The one action that takes `from` to `to` in one timestep, or nullopt when none does (a move
// not in the faced direction, a move and a turn at once, a half turn, a jump, an obstacle).
std::optional<Action> action_between(const Grid& grid, Pose from, Pose to);

}  // namespace gdrhcr
