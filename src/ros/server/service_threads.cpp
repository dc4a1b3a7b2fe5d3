// One callback queue and one spinner thread per group of services and timers.
#include "service_threads.h"

namespace fragg::ros {

ServiceThreads::~ServiceThreads() { stop(); }

::ros::NodeHandle ServiceThreads::handle(const ::ros::NodeHandle& nh, const std::string& group) {
  std::unique_ptr<Group>& g = groups_[group];
  if (!g) {
    g = std::make_unique<Group>();
    g->spinner = std::make_unique<::ros::AsyncSpinner>(1, &g->queue);
    g->spinner->start();
  }
  ::ros::NodeHandle copy(nh);
  copy.setCallbackQueue(&g->queue);
  return copy;
}

void ServiceThreads::stop() {
  for (auto& [name, g] : groups_)
    if (g->spinner) {
      g->spinner->stop();  // joins: a callback in flight finishes first
      g->spinner.reset();
    }
}

}  // namespace fragg::ros
