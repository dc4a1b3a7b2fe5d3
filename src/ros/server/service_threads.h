// Callback queues of the map server's own, each with one thread (ros::AsyncSpinner), so that
// its services and timers run side by side: a long ~get_frontiers, ~check_collision batch or
// .bt save occupies its own group's thread only, and ~get_stats (a group of its own) answers
// meanwhile. The cloud input has its own queue and thread as well (cloud_input.h). A group is
// a name; handle(group) gives a copy of a node handle whose callbacks (services, timers,
// subscriber-status callbacks) go to that group's queue. One thread a group keeps a group's
// callbacks in order (one ~save_map after the other), as the node's single queue did.
//
// Lifetime: stop() joins every thread (callbacks in flight finish first); the queues stay until
// the object goes, so that the services and timers advertised on them can be shut down after
// stop(). MapServer stops the threads before anything their callbacks use goes away.
#pragma once

#include <ros/callback_queue.h>
#include <ros/node_handle.h>
#include <ros/spinner.h>

#include <map>
#include <memory>
#include <string>

namespace fragg::ros {

class ServiceThreads {
 public:
  ServiceThreads() = default;
  ~ServiceThreads();  ///< stop()
  ServiceThreads(const ServiceThreads&) = delete;
  ServiceThreads& operator=(const ServiceThreads&) = delete;

  /// A copy of `nh` (same namespace and remappings) whose callbacks go to `group`'s queue; the
  /// group's queue and thread are made on first use and its thread runs from then on.
  [[nodiscard]] ::ros::NodeHandle handle(const ::ros::NodeHandle& nh, const std::string& group);
  /// Joins every group's thread; no callback of theirs runs after it returns. Idempotent.
  void stop();
  /// The groups made so far.
  [[nodiscard]] size_t groupCount() const { return groups_.size(); }

 private:
  struct Group {
    ::ros::CallbackQueue queue;
    std::unique_ptr<::ros::AsyncSpinner> spinner;
  };
  std::map<std::string, std::unique_ptr<Group>> groups_;
};

}  // namespace fragg::ros
