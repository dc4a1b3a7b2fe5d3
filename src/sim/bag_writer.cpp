#include "fragg_map/sim/bag_writer.h"

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Path.h>
#include <rosbag/bag.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_msgs/TFMessage.h>

#include <cstring>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg::sim {
namespace {

geometry_msgs::Transform toTransform(const Eigen::Isometry3d& T) {
  geometry_msgs::Transform t;
  const Eigen::Quaterniond q(T.linear());
  t.translation.x = T.translation().x();
  t.translation.y = T.translation().y();
  t.translation.z = T.translation().z();
  t.rotation.x = q.x();
  t.rotation.y = q.y();
  t.rotation.z = q.z();
  t.rotation.w = q.w();
  return t;
}

geometry_msgs::Pose toPose(const Eigen::Isometry3d& T) {
  const geometry_msgs::Transform t = toTransform(T);
  geometry_msgs::Pose p;
  p.position.x = t.translation.x;
  p.position.y = t.translation.y;
  p.position.z = t.translation.z;
  p.orientation = t.rotation;
  return p;
}

geometry_msgs::TransformStamped stamped(const std::string& parent, const std::string& child,
                                        const Eigen::Isometry3d& T, const ros::Time& stamp) {
  geometry_msgs::TransformStamped m;
  m.header.frame_id = parent;
  m.header.stamp = stamp;
  m.child_frame_id = child;
  m.transform = toTransform(T);
  return m;
}

sensor_msgs::PointField field(const std::string& name, uint32_t offset, uint8_t type) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = type;
  f.count = 1;
  return f;
}

}  // namespace

struct SimBagWriter::Impl {
  rosbag::Bag bag;
  BagNames names;
  bool rings = false;
  nav_msgs::Path path;
  ros::Time last;
  bool open = false;
};

SimBagWriter::SimBagWriter(const std::string& path, const BagNames& names,
                           const Eigen::Isometry3d& T_base_sensor, bool lidar_rings)
    : impl_(std::make_unique<Impl>()) {
  impl_->names = names;
  impl_->rings = lidar_rings;
  try {
    impl_->bag.open(path, rosbag::bagmode::Write);
  } catch (const rosbag::BagException& e) {
    throw IoError(path + ": cannot write bag: " + e.what());
  }
  impl_->open = true;
  const ros::Time start(names.start_s);
  tf2_msgs::TFMessage tf_static;
  tf_static.transforms.push_back(
      stamped(names.base_frame, names.sensor_frame, T_base_sensor, start));
  impl_->bag.write("/tf_static", start, tf_static);
  impl_->path.header.frame_id = names.map_frame;
  impl_->last = start;
}

SimBagWriter::~SimBagWriter() {
  if (impl_ && impl_->open) impl_->bag.close();
}

void SimBagWriter::add(const PointCloud& cloud_S, const PoseSample& pose) {
  const BagNames& n = impl_->names;
  const ros::Time stamp(n.start_s + pose.stamp_s);
  impl_->last = stamp;
  tf2_msgs::TFMessage tf;
  tf.transforms.push_back(stamped(n.map_frame, n.odom_frame, Eigen::Isometry3d::Identity(), stamp));
  tf.transforms.push_back(stamped(n.odom_frame, n.base_frame, pose.T_odom_base, stamp));
  impl_->bag.write("/tf", stamp, tf);

  geometry_msgs::PoseStamped gt;
  gt.header.frame_id = n.map_frame;
  gt.header.stamp = stamp;
  gt.header.seq = static_cast<uint32_t>(impl_->path.poses.size());
  gt.pose = toPose(pose.T_map_base);
  impl_->bag.write(n.gt_pose_topic, stamp, gt);
  impl_->path.poses.push_back(gt);

  sensor_msgs::PointCloud2 msg;
  msg.header.frame_id = n.sensor_frame;
  msg.header.stamp = stamp;
  msg.header.seq = gt.header.seq;
  msg.height = cloud_S.organised() ? cloud_S.height : 1;
  msg.width = cloud_S.organised() ? cloud_S.width : static_cast<uint32_t>(cloud_S.size());
  msg.fields = {field("x", 0, sensor_msgs::PointField::FLOAT32),
                field("y", 4, sensor_msgs::PointField::FLOAT32),
                field("z", 8, sensor_msgs::PointField::FLOAT32)};
  msg.point_step = 12;
  if (impl_->rings) {
    msg.fields.push_back(field("ring", 12, sensor_msgs::PointField::UINT16));
    msg.point_step = 16;
  }
  msg.is_bigendian = false;
  msg.row_step = msg.point_step * msg.width;
  msg.is_dense = true;
  msg.data.assign(size_t{msg.row_step} * msg.height, 0);
  for (size_t i = 0; i < cloud_S.size(); ++i) {
    uint8_t* p = msg.data.data() + i * msg.point_step;
    const Eigen::Vector3f& q = cloud_S.points_S[i];
    if (!q.allFinite()) msg.is_dense = false;
    std::memcpy(p, q.data(), 12);
    if (impl_->rings) {
      const uint16_t ring = static_cast<uint16_t>(i / msg.width);
      std::memcpy(p + 12, &ring, 2);
    }
  }
  impl_->bag.write(n.cloud_topic, stamp, msg);
}

void SimBagWriter::finish() {
  impl_->path.header.stamp = impl_->last;
  impl_->bag.write(impl_->names.gt_path_topic, impl_->last, impl_->path);
  impl_->bag.close();
  impl_->open = false;
}

}  // namespace fragg::sim
