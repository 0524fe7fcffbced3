#include "gd_rhcr_planner/map_loader.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

namespace gd_rhcr_planner {

using gdrhcr::MapError;

int MapFrame::cell_x(double wx) const {
  return static_cast<int>(std::floor((wx - origin_x) / resolution));
}
int MapFrame::cell_y(double wy) const {
  return height - 1 - static_cast<int>(std::floor((wy - origin_y) / resolution));
}

namespace {

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Next header token of a PGM file, skipping whitespace and '#' comments.
std::string pgm_token(std::istream& in, const std::string& path) {
  std::string tok;
  int ch;
  while ((ch = in.get()) != EOF) {
    if (ch == '#') {
      while ((ch = in.get()) != EOF && ch != '\n') {}
      continue;
    }
    if (std::isspace(ch)) {
      if (!tok.empty()) return tok;
      continue;
    }
    tok.push_back(static_cast<char>(ch));
  }
  if (tok.empty()) throw MapError(path + ": truncated PGM header");
  return tok;
}

int pgm_int(std::istream& in, const std::string& path, const char* what) {
  const std::string tok = pgm_token(in, path);
  try {
    size_t used = 0;
    const int v = std::stoi(tok, &used);
    if (used != tok.size() || v <= 0) throw std::invalid_argument(tok);
    return v;
  } catch (const std::exception&) {
    throw MapError(path + ": bad PGM " + what + " '" + tok + "'");
  }
}

}  // namespace

PgmImage read_pgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapError(path + ": cannot open image");
  const std::string magic = pgm_token(in, path);
  if (magic != "P5" && magic != "P2")
    throw MapError(path + ": not a PGM image (magic '" + magic + "'; only P2/P5 are supported)");
  PgmImage img;
  img.width = pgm_int(in, path, "width");
  img.height = pgm_int(in, path, "height");
  img.maxval = pgm_int(in, path, "maxval");
  if (img.maxval > 65535) throw MapError(path + ": PGM maxval above 65535");
  if (static_cast<long>(img.width) * img.height > (1L << 28)) throw MapError(path + ": image too large");
  img.pixels.resize(static_cast<size_t>(img.width) * img.height);
  if (magic == "P5") {
    const int bytes = img.maxval < 256 ? 1 : 2;
    for (auto& p : img.pixels) {
      int v = in.get();
      if (bytes == 2 && v != EOF) v = (v << 8) | in.get();
      if (!in) throw MapError(path + ": truncated PGM data");
      p = v;
    }
  } else {
    for (auto& p : img.pixels) {
      if (!(in >> p)) throw MapError(path + ": truncated PGM data");
    }
  }
  return img;
}

gdrhcr::Grid grid_from_pgm(const PgmImage& img, bool negate, double occupied_thresh,
                           double free_thresh, const std::string& name) {
  std::vector<std::string> rows(img.height, std::string(img.width, '@'));
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const int v = img.pixels[static_cast<size_t>(y) * img.width + x];
      const double p = negate ? double(v) / img.maxval : double(img.maxval - v) / img.maxval;
      if (p < free_thresh && !(p > occupied_thresh)) rows[y][x] = '.';
    }
  return gdrhcr::Grid::from_rows(rows, name);
}

LoadedMap load_map(const std::string& path, double cell_size) {
  if (!(cell_size > 0)) throw MapError(path + ": cell size must be > 0 metres");
  if (!ends_with(path, ".yaml") && !ends_with(path, ".yml")) {
    gdrhcr::Grid grid = gdrhcr::Grid::load(path);
    MapFrame frame;
    frame.resolution = cell_size;
    frame.height = grid.height();
    const std::string fmt = grid.endpoints().empty() && grid.homes().empty() ? "movingai" : "kiva";
    return LoadedMap{std::move(grid), frame, path, fmt};
  }
  YAML::Node doc;
  try {
    doc = YAML::LoadFile(path);
  } catch (const std::exception& e) {
    throw MapError(path + ": cannot read map YAML: " + e.what());
  }
  try {
    if (!doc["image"] || !doc["resolution"])
      throw MapError(path + ": map YAML needs 'image' and 'resolution'");
    std::string image = doc["image"].as<std::string>();
    if (!image.empty() && image[0] != '/') {
      const auto slash = path.find_last_of('/');
      image = (slash == std::string::npos ? std::string(".") : path.substr(0, slash)) + "/" + image;
    }
    MapFrame frame;
    frame.resolution = doc["resolution"].as<double>();
    if (!(frame.resolution > 0)) throw MapError(path + ": resolution must be > 0");
    if (doc["origin"]) {
      auto o = doc["origin"];
      if (!o.IsSequence() || o.size() < 2) throw MapError(path + ": origin must be [x, y, yaw]");
      frame.origin_x = o[0].as<double>();
      frame.origin_y = o[1].as<double>();
      frame.origin_yaw = o.size() > 2 ? o[2].as<double>() : 0.0;
      if (frame.origin_yaw != 0.0) throw MapError(path + ": rotated map origins are not supported");
    }
    const bool negate = doc["negate"] ? doc["negate"].as<int>() != 0 : false;
    const double occ = doc["occupied_thresh"] ? doc["occupied_thresh"].as<double>() : 0.65;
    const double fre = doc["free_thresh"] ? doc["free_thresh"].as<double>() : 0.196;
    if (doc["mode"] && doc["mode"].as<std::string>() != "trinary")
      throw MapError(path + ": only mode 'trinary' is supported");
    PgmImage img = read_pgm(image);
    gdrhcr::Grid grid = grid_from_pgm(img, negate, occ, fre, path);
    frame.height = grid.height();
    return LoadedMap{std::move(grid), frame, path, "map_server"};
  } catch (const YAML::Exception& e) {
    throw MapError(path + ": bad map YAML: " + e.what());
  }
}

}  // namespace gd_rhcr_planner
