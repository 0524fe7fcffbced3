#include "gd_rhcr_planner/task_store.hpp"

#include <cerrno>
#include <cstring>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace gd_rhcr_planner {
namespace {

constexpr int kVersion = 1;

nlohmann::json to_json(const TaskRecord& t) {
  return {{"id", t.id},
          {"pickup", {t.pickup_x, t.pickup_y}},
          {"delivery", {t.delivery_x, t.delivery_y}},
          {"priority", t.priority},
          {"state", t.state},
          {"robot", t.robot}};
}

TaskRecord from_json(const nlohmann::json& j) {
  TaskRecord t;
  t.id = j.at("id").get<uint64_t>();
  t.pickup_x = j.at("pickup").at(0).get<int>();
  t.pickup_y = j.at("pickup").at(1).get<int>();
  t.delivery_x = j.at("delivery").at(0).get<int>();
  t.delivery_y = j.at("delivery").at(1).get<int>();
  t.priority = j.at("priority").get<int>();
  t.state = j.at("state").get<uint8_t>();
  t.robot = j.at("robot").get<int>();
  if (t.state > kCancelled) throw std::runtime_error("unknown task state " + std::to_string(t.state));
  return t;
}

std::runtime_error store_error(const std::string& path, const std::string& what) {
  return std::runtime_error("task store " + path + ": " + what);
}

}  // namespace

StoredTasks TaskStore::read(const std::string& path) {
  StoredTasks out;
  std::ifstream in(path);
  if (!in) return out;  // no store yet: nothing to restore
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  const bool torn_tail = in.eof() && !lines.empty() && !lines.back().empty() && [&] {
    in.clear();
    in.seekg(-1, std::ios::end);
    char c = 0;
    in.get(c);
    return c != '\n';
  }();
  std::map<uint64_t, TaskRecord> open;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].empty()) continue;
    try {
      const auto j = nlohmann::json::parse(lines[i]);
      if (j.contains("version")) {  // header of a compacted journal
        if (j.at("version").get<int>() != kVersion)
          throw std::runtime_error("unsupported version " + j.at("version").dump());
        out.delivered = j.value("delivered", uint64_t{0});
        out.failed = j.value("failed", uint64_t{0});
        out.next_id = std::max(out.next_id, j.value("next_id", uint64_t{1}));
        continue;
      }
      TaskRecord t = from_json(j);
      out.next_id = std::max(out.next_id, t.id + 1);
      if (task_finished(t.state)) {
        open.erase(t.id);
        if (t.state == kDelivered) ++out.delivered;
        if (t.state == kFailed) ++out.failed;
      } else {
        open[t.id] = t;
      }
    } catch (const std::exception& e) {
      if (i + 1 == lines.size() && torn_tail) {
        out.warnings.push_back("ignored a torn last line (" + std::to_string(lines[i].size()) +
                               " bytes) of " + path + ", written during a crash");
        break;
      }
      throw store_error(path, "line " + std::to_string(i + 1) + " is damaged: " + e.what());
    }
  }
  for (auto& [id, t] : open) out.open.push_back(t);
  return out;
}

TaskStore::TaskStore(const std::string& path) : path_(path) {
  if (path_.empty()) throw std::runtime_error("task store: empty path");
  const auto dir = std::filesystem::path(path_).parent_path();
  std::error_code ec;
  if (!dir.empty()) std::filesystem::create_directories(dir, ec);
  if (ec) throw store_error(path_, "cannot create directory " + dir.string() + ": " + ec.message());
  loaded_ = read(path_);
  // Start from a compact journal of what was loaded (this also drops a torn tail).
  const std::string tmp = path_ + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    if (!out) throw store_error(path_, std::string("cannot write ") + tmp + ": " + std::strerror(errno));
    out << nlohmann::json{{"version", kVersion}, {"delivered", loaded_.delivered}, {"failed", loaded_.failed},
                          {"next_id", loaded_.next_id}}.dump()
        << '\n';
    for (auto& t : loaded_.open) out << to_json(t).dump() << '\n';
    out.flush();
    if (!out) throw store_error(path_, "write error on " + tmp);
  }
  std::filesystem::rename(tmp, path_, ec);
  if (ec) throw store_error(path_, "cannot replace the journal: " + ec.message());
  lines_ = 1 + loaded_.open.size();
  next_id_ = loaded_.next_id;
  open_append();
}

TaskStore::~TaskStore() {
  if (file_) std::fclose(file_);
}

void TaskStore::open_append() {
  if (file_) std::fclose(file_);
  file_ = std::fopen(path_.c_str(), "a");
  if (!file_) throw store_error(path_, std::string("cannot open for appending: ") + std::strerror(errno));
}

void TaskStore::record(const std::vector<TaskEvent>& events, const Fleet& fleet) {
  if (events.empty()) return;
  for (const TaskEvent& e : events) {
    const TaskRecord* t = fleet.task(e.task_id);
    if (!t) continue;  // already forgotten (finished long ago)
    TaskRecord r = *t;
    r.state = e.state;  // the event's state: later events of the batch follow in order
    r.robot = e.robot;
    next_id_ = std::max(next_id_, r.id + 1);
    const std::string line = to_json(r).dump() + "\n";
    if (std::fwrite(line.data(), 1, line.size(), file_) != line.size())
      throw store_error(path_, std::string("write error: ") + std::strerror(errno));
    ++lines_;
  }
  if (std::fflush(file_) != 0) throw store_error(path_, std::string("flush error: ") + std::strerror(errno));
  const size_t open = fleet.count_in_state(kQueued) + fleet.count_in_state(kAssigned) + fleet.count_in_state(kPicked);
  if (lines_ > 4 * open + 4096) compact(fleet);
}

void TaskStore::compact(const Fleet& fleet) {
  const std::string tmp = path_ + ".tmp";
  std::FILE* out = std::fopen(tmp.c_str(), "w");
  if (!out) throw store_error(path_, std::string("cannot write ") + tmp + ": " + std::strerror(errno));
  std::string text =
      nlohmann::json{{"version", kVersion}, {"delivered", fleet.delivered_total()}, {"failed", fleet.failed_total()},
                     {"next_id", std::max(next_id_, fleet.next_id())}}
          .dump() + "\n";
  const auto open = fleet.open_tasks();
  for (auto& t : open) text += to_json(t).dump() + "\n";
  const bool ok = std::fwrite(text.data(), 1, text.size(), out) == text.size() && std::fflush(out) == 0;
  std::fclose(out);
  if (!ok) throw store_error(path_, "write error on " + tmp);
  std::error_code ec;
  std::filesystem::rename(tmp, path_, ec);
  if (ec) throw store_error(path_, "cannot replace the journal: " + ec.message());
  lines_ = 1 + open.size();
  open_append();
}

}  // namespace gd_rhcr_planner
