// The task store: accepted tasks survive a restart of the planner node. An append-only journal
// of JSON lines, one self-contained record per task status change (id, cells, priority, state,
// robot), flushed before the node answers the request that caused it; replay keeps each task's
// last record and drops finished tasks. When the journal grows past a few times the number of
// open tasks it is compacted: rewritten as one record per open task into a temporary file that
// then replaces it (rename is atomic), so a crash at any moment leaves a readable store. A torn
// last line (a crash mid-write) is ignored with a warning; damage anywhere else is an error that
// names the file and line, so tasks are never dropped silently.
// ROS-free; unit-tested in test/task_store_test.cpp.
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "gd_rhcr_planner/fleet.hpp"

namespace gd_rhcr_planner {

struct StoredTasks {
  std::vector<TaskRecord> open;  // unfinished tasks in id order, with state and robot
  uint64_t delivered = 0, failed = 0;
  uint64_t next_id = 1;  // above every id the store has seen, so ids are not reused
  std::vector<std::string> warnings;
};

class TaskStore {
 public:
  // Opens (creating when missing) the store at `path`. Throws std::runtime_error naming the
  // path when the directory or file cannot be written or the file is damaged.
  explicit TaskStore(const std::string& path);
  ~TaskStore();
  TaskStore(const TaskStore&) = delete;
  TaskStore& operator=(const TaskStore&) = delete;

  // The tasks found at open.
  const StoredTasks& loaded() const { return loaded_; }
  // Appends one record per event (the task's current fields from `fleet`), flushes, and
  // compacts when the journal is long. Throws std::runtime_error on a write error.
  void record(const std::vector<TaskEvent>& events, const Fleet& fleet);
  const std::string& path() const { return path_; }
  size_t journal_lines() const { return lines_; }

  // Reads a store without opening it for writing (tests, tools).
  static StoredTasks read(const std::string& path);

 private:
  void compact(const Fleet& fleet);
  void open_append();

  std::string path_;
  std::FILE* file_ = nullptr;
  size_t lines_ = 0;
  uint64_t next_id_ = 1;  // above every id recorded
  StoredTasks loaded_;
};

}  // namespace gd_rhcr_planner
