#include "gdrhcr/action_model.hpp"

#include <stdexcept>

namespace gdrhcr {

namespace {
constexpr int kDx[4] = {1, 0, -1, 0};  // east, south, west, north (LoRR's orientation order)
constexpr int kDy[4] = {0, 1, 0, -1};
}  // namespace

ActionModel parse_action_model(const std::string& text) {
  if (text == "mapf") return ActionModel::kMapf;
  if (text == "rotation") return ActionModel::kRotation;
  throw std::invalid_argument("action model must be one of mapf, rotation; got '" + quote_input(text) + "'");
}

const char* action_model_name(ActionModel model) {
  return model == ActionModel::kRotation ? "rotation" : "mapf";
}

const char* heading_name(Heading h) {
  switch (h) {
    case kEast: return "E";
    case kSouth: return "S";
    case kWest: return "W";
    case kNorth: return "N";
    default: return "?";
  }
}

Cell forward_cell(const Grid& grid, Cell c, Heading h) {
  if (!grid.valid_cell(c) || h < 0 || h > 3) return kNoCell;
  const int x = grid.x_of(c) + kDx[h], y = grid.y_of(c) + kDy[h];
  if (!grid.in_bounds(x, y)) return kNoCell;
  const Cell n = grid.cell(x, y);
  return grid.is_free(n) ? n : kNoCell;
}

Heading heading_of_move(const Grid& grid, Cell from, Cell to) {
  if (!grid.valid_cell(from) || !grid.valid_cell(to)) return kNoHeading;
  const int dx = grid.x_of(to) - grid.x_of(from), dy = grid.y_of(to) - grid.y_of(from);
  for (Heading h = 0; h < kNumHeadings; ++h)
    if (dx == kDx[h] && dy == kDy[h]) return h;
  return kNoHeading;
}

Pose apply_action(const Grid& grid, Pose p, Action a) {
  switch (a) {
    case Action::kForward: return {forward_cell(grid, p.cell, p.heading), p.heading};
    case Action::kClockwise: return {p.cell, rotate_cw(p.heading)};
    case Action::kCounterClockwise: return {p.cell, rotate_ccw(p.heading)};
    case Action::kWait: break;
  }
  return p;
}

std::optional<Action> action_between(const Grid& grid, Pose from, Pose to) {
  if (from.heading < 0 || from.heading > 3 || to.heading < 0 || to.heading > 3) return std::nullopt;
  if (!grid.is_free(from.cell) || !grid.is_free(to.cell)) return std::nullopt;
  if (from.cell != to.cell) {
    if (to.heading != from.heading || forward_cell(grid, from.cell, from.heading) != to.cell) return std::nullopt;
    return Action::kForward;
  }
  if (to.heading == from.heading) return Action::kWait;
  if (to.heading == rotate_cw(from.heading)) return Action::kClockwise;
  if (to.heading == rotate_ccw(from.heading)) return Action::kCounterClockwise;
  return std::nullopt;
}

}  // namespace gdrhcr
