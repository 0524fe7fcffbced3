#include "gd_rhcr_planner/fleet_markers.hpp"

#include <cmath>
#include <cstdio>
#include <map>

#include <ros/serialization.h>

namespace gd_rhcr_planner {

using gdrhcr::Cell;
using visualization_msgs::Marker;

std_msgs::ColorRGBA group_colour(int i, float alpha) {
  const double h = std::fmod(i * 0.618033988749895, 1.0) * 6.0;
  const double s = 0.8, v = 1.0;
  const int k = static_cast<int>(h);
  const double f = h - k, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r, g, b;
  switch (k % 6) {
    case 0: r = v, g = t, b = p; break;
    case 1: r = q, g = v, b = p; break;
    case 2: r = p, g = v, b = t; break;
    case 3: r = p, g = q, b = v; break;
    case 4: r = t, g = p, b = v; break;
    default: r = v, g = p, b = q; break;
  }
  std_msgs::ColorRGBA c;
  c.r = r, c.g = g, c.b = b, c.a = alpha;
  return c;
}

namespace {
std_msgs::ColorRGBA rgba(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r, c.g = g, c.b = b, c.a = a;
  return c;
}

std::vector<uint8_t> bytes_of(const Marker& m) {
  const uint32_t n = ros::serialization::serializationLength(m);
  std::vector<uint8_t> buf(n);
  ros::serialization::OStream s(buf.data(), n);
  ros::serialization::serialize(s, m);
  return buf;
}
}  // namespace

FleetMarkers::FleetMarkers(const gdrhcr::Grid& grid, const MapFrame& frame, MarkerStyle style)
    : grid_(grid), frame_(frame), style_(std::move(style)) {}

geometry_msgs::Point FleetMarkers::point(Cell c, double z) const {
  geometry_msgs::Point p;
  p.x = frame_.world_x(grid_.x_of(c));
  p.y = frame_.world_y(grid_.y_of(c));
  p.z = z;
  return p;
}

Marker FleetMarkers::base(const std::string& ns, int type, int id) const {
  Marker m;
  m.header.frame_id = style_.frame_id;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.scale.x = m.scale.y = m.scale.z = 1.0;
  return m;
}

void FleetMarkers::emit(std::vector<Marker>& all, Marker m) const {
  const bool list = m.type == Marker::LINE_LIST || m.type == Marker::CUBE_LIST ||
                    m.type == Marker::SPHERE_LIST || m.type == Marker::TRIANGLE_LIST;
  if (list && m.points.empty()) {  // rviz rejects empty lists: delete the layer instead
    m.action = Marker::DELETE;
    m.colors.clear();
  }
  all.push_back(std::move(m));
}

void FleetMarkers::set_stations(const std::vector<Cell>& pickups, const std::vector<Cell>& deliveries) {
  const double res = frame_.resolution;
  stations_.clear();
  auto pick = base("stations", Marker::CUBE_LIST, 0);
  pick.scale.x = pick.scale.y = 0.7 * res;
  pick.scale.z = 0.02 * res;
  pick.color = rgba(1.0, 0.55, 0.0, 0.22);
  for (Cell c : pickups) pick.points.push_back(point(c, 0.0));
  auto drop = base("stations", Marker::CUBE_LIST, 1);
  drop.scale = pick.scale;
  drop.color = rgba(0.1, 0.9, 0.3, 0.45);
  for (Cell c : deliveries) drop.points.push_back(point(c, 0.0));
  emit(stations_, pick);
  emit(stations_, drop);
}


visualization_msgs::MarkerArray FleetMarkers::update(const FleetView& v) {
  std::vector<Marker> all = stations_;
  robots_layer(v, all);
  groups_layer(v, all);
  paths_layer(v, all);
  goal_lines_layer(v, all);
  tasks_layer(v, all);
  operator_layer(v, all);
  labels_layer(v, all);
  overlay_layer(v, all);
  return changes(std::move(all));
}

// Robots: a triangle per robot pointing along its heading: the one it reports (issue 23), else
// the move it makes, else its last move.
void FleetMarkers::robots_layer(const FleetView& v, std::vector<Marker>& all) {
  const double res = frame_.resolution;
  const size_t n = v.pos.size();
  heading_.resize(n, M_PI / 2);
  auto robots = base("robots", Marker::TRIANGLE_LIST);
  for (size_t r = 0; r < n; ++r) {
    auto p = point(v.pos[r], 0.3 * res);
    if (r < v.heading.size() && v.heading[r] != gdrhcr::kNoHeading) {
      heading_[r] = heading_yaw(v.heading[r]);
    } else if (r < v.next.size() && v.next[r] != v.pos[r] && v.next[r] != gdrhcr::kNoCell) {
      auto q = point(v.next[r], 0.3 * res);
      heading_[r] = std::atan2(q.y - p.y, q.x - p.x);
    }
    const double h = heading_[r], a = 0.62 * res, b = 0.5 * res;
    const bool off = r < v.offline.size() && v.offline[r];
    const auto colour = off ? rgba(0.35, 0.35, 0.35, 1) : group_colour(r < v.group_of.size() ? v.group_of[r] : int(r));
    const double ang[3] = {h, h + 2.45, h - 2.45};
    const double len[3] = {a, b, b};
    for (int k = 0; k < 3; ++k) {
      geometry_msgs::Point c = p;
      c.x += len[k] * std::cos(ang[k]);
      c.y += len[k] * std::sin(ang[k]);
      robots.points.push_back(c);
      robots.colors.push_back(colour);
    }
  }
  emit(all, robots);
}

// Group links: each member to the nearest earlier member of its group (a spanning tree).
void FleetMarkers::groups_layer(const FleetView& v, std::vector<Marker>& all) const {
  const double res = frame_.resolution;
  auto links = base("groups", Marker::LINE_LIST);
  links.scale.x = 0.12 * res;
  std::map<int, std::vector<size_t>> members;
  for (size_t r = 0; r < v.pos.size() && r < v.group_of.size(); ++r)
    if (!(r < v.offline.size() && v.offline[r])) members[v.group_of[r]].push_back(r);
  for (auto& [g, m] : members) {
    if (m.size() < 2) continue;
    auto colour = group_colour(g, 0.9f);
    for (size_t i = 1; i < m.size(); ++i) {
      size_t best = m[0];
      int best_d = INT32_MAX;
      for (size_t j = 0; j < i; ++j) {
        const int d = std::abs(grid_.x_of(v.pos[m[i]]) - grid_.x_of(v.pos[m[j]])) +
                      std::abs(grid_.y_of(v.pos[m[i]]) - grid_.y_of(v.pos[m[j]]));
        if (d < best_d) best_d = d, best = m[j];
      }
      links.points.push_back(point(v.pos[m[i]], 0.25 * res));
      links.points.push_back(point(v.pos[best], 0.25 * res));
      links.colors.push_back(colour);
      links.colors.push_back(colour);
    }
  }
  emit(all, links);
}

// Planned paths along the aisles; the next step when there is no path.
void FleetMarkers::paths_layer(const FleetView& v, std::vector<Marker>& all) const {
  const double res = frame_.resolution;
  auto paths = base("paths", Marker::LINE_LIST);
  paths.scale.x = 0.1 * res;
  for (size_t r = 0; r < v.pos.size(); ++r) {
    auto colour = group_colour(r < v.group_of.size() ? v.group_of[r] : int(r), 0.55f);
    std::vector<Cell> path;
    if (r < v.paths.size() && v.paths[r].size() > 1) path = v.paths[r];
    else if (r < v.next.size() && v.next[r] != v.pos[r]) path = {v.pos[r], v.next[r]};
    for (size_t t = 1; t < path.size(); ++t) {
      if (path[t] == path[t - 1] || path[t] == gdrhcr::kNoCell || path[t - 1] == gdrhcr::kNoCell) continue;
      paths.points.push_back(point(path[t - 1], 0.15 * res));
      paths.points.push_back(point(path[t], 0.15 * res));
      paths.colors.push_back(colour);
      paths.colors.push_back(colour);
    }
  }
  emit(all, paths);
}

void FleetMarkers::goal_lines_layer(const FleetView& v, std::vector<Marker>& all) const {
  const double res = frame_.resolution;
  auto goal_lines = base("goal_lines", Marker::LINE_LIST);
  goal_lines.scale.x = 0.05 * res;
  if (style_.show_goal_lines)
    for (size_t r = 0; r < v.pos.size() && r < v.goal.size(); ++r) {
      if (v.goal[r] == gdrhcr::kNoCell || v.goal[r] == v.pos[r]) continue;
      auto colour = group_colour(r < v.group_of.size() ? v.group_of[r] : int(r), 0.35f);
      goal_lines.points.push_back(point(v.pos[r], 0.3 * res));
      goal_lines.points.push_back(point(v.goal[r], 0.05 * res));
      goal_lines.colors.push_back(colour);
      goal_lines.colors.push_back(colour);
    }
  emit(all, goal_lines);
}

// Open tasks: pickups waiting for a robot, deliveries of loads under way.
void FleetMarkers::tasks_layer(const FleetView& v, std::vector<Marker>& all) const {
  const double res = frame_.resolution;
  auto tp = base("tasks", Marker::CUBE_LIST, 0);
  tp.scale.x = tp.scale.y = 0.8 * res;
  tp.scale.z = 0.04 * res;
  tp.color = rgba(1.0, 0.55, 0.0, 0.85);
  for (Cell c : v.task_pickups) tp.points.push_back(point(c, 0.02 * res));
  auto td = base("tasks", Marker::CUBE_LIST, 1);
  td.scale = tp.scale;
  td.color = rgba(0.1, 0.9, 0.3, 0.85);
  for (Cell c : v.task_deliveries) td.points.push_back(point(c, 0.02 * res));
  emit(all, tp);
  emit(all, td);
}

// A closed outline through the corners (x0, y0)-(x1, y1) at height z, as LINE_LIST segments.
static void outline(Marker& m, double x0, double y0, double x1, double y1, double z) {
  const double xs[5] = {x0, x1, x1, x0, x0}, ys[5] = {y0, y0, y1, y1, y0};
  for (int k = 0; k < 4; ++k) {
    geometry_msgs::Point a, b;
    a.x = xs[k], a.y = ys[k], b.x = xs[k + 1], b.y = ys[k + 1];
    a.z = b.z = z;
    m.points.push_back(a);
    m.points.push_back(b);
  }
}

// Operator state: paused robots framed in yellow; the whole map in red on emergency stop.
void FleetMarkers::operator_layer(const FleetView& v, std::vector<Marker>& all) const {
  const double res = frame_.resolution;
  auto frames = base("operator", Marker::LINE_LIST, 0);
  frames.scale.x = 0.12 * res;
  frames.color = rgba(1.0, 0.9, 0.1, 1.0);
  if (!v.emergency_stop)
    for (size_t r = 0; r < v.pos.size() && r < v.held.size(); ++r)
      if (v.held[r]) {
        const auto p = point(v.pos[r], 0);
        const double half = 0.55 * res;
        outline(frames, p.x - half, p.y - half, p.x + half, p.y + half, 0.35 * res);
      }
  emit(all, frames);
  auto stop = base("operator", Marker::LINE_LIST, 1);
  stop.scale.x = 0.6 * res;
  stop.color = rgba(1.0, 0.1, 0.1, 1.0);
  if (v.emergency_stop) {  // a rectangle hugging the map
    const double w = grid_.width() * res, h = grid_.height() * res;
    outline(stop, frame_.origin_x - res, frame_.origin_y - res, frame_.origin_x + w + res, frame_.origin_y + h + res, 0);
  }
  emit(all, stop);
}

// Labels (small fleets), one marker per robot; ids beyond the fleet are never used.
void FleetMarkers::labels_layer(const FleetView& v, std::vector<Marker>& all) const {
  const double res = frame_.resolution;
  if (static_cast<int>(v.pos.size()) > style_.label_limit) return;
  for (size_t r = 0; r < v.pos.size(); ++r) {
    auto label = base("labels", Marker::TEXT_VIEW_FACING, static_cast<int>(r));
    label.pose.position = point(v.pos[r], 1.0 * res);
    label.scale.z = 0.6 * res;
    label.color = rgba(1, 1, 1, 1);
    label.text = std::to_string(r);
    all.push_back(label);
  }
}

// The overlay: above the top edge of the map, left-aligned to its middle.
void FleetMarkers::overlay_layer(const FleetView& v, std::vector<Marker>& all) const {
  const double res = frame_.resolution;
  auto text = base("overlay", Marker::TEXT_VIEW_FACING);
  const double w = grid_.width() * res, h = grid_.height() * res;
  text.scale.z = std::max(1.0 * res, std::min(w, h) / 22.0);
  text.pose.position.x = frame_.origin_x + w / 2;
  text.pose.position.y = frame_.origin_y + h + 2.2 * text.scale.z;
  text.pose.position.z = 1.0;
  text.color = v.emergency_stop ? rgba(1, 0.3, 0.3, 1) : rgba(0.95, 0.95, 0.95, 1);
  text.text = v.overlay.empty() ? " " : v.overlay;
  all.push_back(text);
}

visualization_msgs::MarkerArray FleetMarkers::changes(std::vector<Marker>&& all) {
  visualization_msgs::MarkerArray out;
  std::vector<std::vector<uint8_t>> bytes;
  bytes.reserve(all.size());
  for (auto& m : all) bytes.push_back(bytes_of(m));
  std::map<std::pair<std::string, int>, size_t> before;
  for (size_t i = 0; i < last_.size(); ++i) before[{last_[i].ns, last_[i].id}] = i;
  for (size_t i = 0; i < all.size(); ++i) {
    auto it = before.find({all[i].ns, all[i].id});
    if (it != before.end() && last_bytes_[it->second] == bytes[i]) continue;
    out.markers.push_back(all[i]);
  }
  // Markers that are gone (labels of a fleet grown past label_limit): delete them.
  std::map<std::pair<std::string, int>, bool> now;
  for (auto& m : all) now[{m.ns, m.id}] = true;
  for (auto& m : last_)
    if (!now.count({m.ns, m.id})) {
      auto d = base(m.ns, m.type, m.id);
      d.action = Marker::DELETE;
      out.markers.push_back(d);
    }
  last_ = std::move(all);
  last_bytes_ = std::move(bytes);
  return out;
}

}  // namespace gd_rhcr_planner
