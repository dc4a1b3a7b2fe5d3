// fragg_map_server: a node that only loads fragg_map/MapServerNodelet into itself (the node's
// name, remappings and private parameters are passed on).
#include <nodelet/loader.h>
#include <ros/ros.h>

#include <map>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  ros::init(argc, argv, "fragg_map");
  nodelet::Loader loader;
  const nodelet::M_string remappings = ros::names::getRemappings();
  const nodelet::V_string args(argv + 1, argv + argc);
  if (!loader.load(ros::this_node::getName(), "fragg_map/MapServerNodelet", remappings, args)) {
    ROS_FATAL("fragg_map_server: could not load fragg_map/MapServerNodelet");
    return 1;
  }
  ros::spin();
  return 0;
}
