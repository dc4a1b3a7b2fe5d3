// ROS bag reader (fragg_map_rosbag, built with ROS only): sensor_msgs/PointCloud2 scans posed by
// the bag's own /tf and /tf_static.
#include "fragg_map/io/rosbag_source.h"

#include <geometry_msgs/TransformStamped.h>
#include <ros/exception.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "fragg_map/errors.h"

namespace fragg {
namespace {

constexpr char kPointCloud2Type[] = "sensor_msgs/PointCloud2";

std::string withoutLeadingSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

std::string joinTopics(const std::set<std::string>& topics) {
  std::string out;
  for (const std::string& topic : topics) out += (out.empty() ? "" : ", ") + topic;
  return out.empty() ? "none" : out;
}

[[noreturn]] void fail(const std::string& path, const std::string& problem) {
  throw IoError(path + ": " + problem);
}

Eigen::Isometry3d toIsometry(const geometry_msgs::Transform& t) {
  Eigen::Quaterniond q(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z);
  q.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  return T;
}

// x y z of a PointCloud2 as float32 or float64 (either byte order); organised clouds keep
// width x height and their NaNs. Throws IoError (naming `where`) on an inconsistent message.
PointCloud cloudFromMessage(const sensor_msgs::PointCloud2& msg, const std::string& where) {
  const sensor_msgs::PointField* fields[3] = {nullptr, nullptr, nullptr};
  static const char* const kNames[3] = {"x", "y", "z"};
  for (const sensor_msgs::PointField& field : msg.fields)
    for (int axis = 0; axis < 3; ++axis)
      if (field.name == kNames[axis]) fields[axis] = &field;
  for (int axis = 0; axis < 3; ++axis) {
    if (!fields[axis]) throw IoError(where + ": PointCloud2 has no " + kNames[axis] + " field");
    const uint8_t type = fields[axis]->datatype;
    if (type != sensor_msgs::PointField::FLOAT32 && type != sensor_msgs::PointField::FLOAT64)
      throw IoError(where + ": PointCloud2 field " + kNames[axis] + " has datatype " +
                    std::to_string(type) + ", expected FLOAT32 (7) or FLOAT64 (8)");
    const uint64_t end =
        uint64_t{fields[axis]->offset} + (type == sensor_msgs::PointField::FLOAT32 ? 4 : 8);
    if (end > msg.point_step)
      throw IoError(where + ": PointCloud2 field " + kNames[axis] + " ends past point_step " +
                    std::to_string(msg.point_step));
  }
  const uint64_t width = msg.width, height = msg.height;
  const uint64_t points = width * height;
  if (points > 0) {
    if (uint64_t{msg.row_step} < width * msg.point_step)
      throw IoError(where + ": PointCloud2 row_step " + std::to_string(msg.row_step) +
                    " < width x point_step");
    if ((height - 1) * msg.row_step + width * msg.point_step > msg.data.size())
      throw IoError(where + ": PointCloud2 data has " + std::to_string(msg.data.size()) +
                    " bytes, too few for " + std::to_string(width) + " x " +
                    std::to_string(height) + " points");
  }
  const bool swap = msg.is_bigendian != (__BYTE_ORDER__ == __ORDER_BIG_ENDIAN__);
  auto load = [swap](const uint8_t* p, bool is_double) -> float {
    uint8_t bytes[8];
    const size_t n = is_double ? 8 : 4;
    std::memcpy(bytes, p, n);
    if (swap)
      for (size_t i = 0; i < n / 2; ++i) std::swap(bytes[i], bytes[n - 1 - i]);
    if (is_double) {
      double v;
      std::memcpy(&v, bytes, 8);
      return static_cast<float>(v);
    }
    float v;
    std::memcpy(&v, bytes, 4);
    return v;
  };
  PointCloud cloud;
  cloud.points_S.resize(points);
  for (uint64_t row = 0; row < height; ++row) {
    const uint8_t* record = msg.data.data() + row * msg.row_step;
    for (uint64_t col = 0; col < width; ++col, record += msg.point_step) {
      Eigen::Vector3f& p = cloud.points_S[row * width + col];
      for (int axis = 0; axis < 3; ++axis)
        p[axis] = load(record + fields[axis]->offset,
                       fields[axis]->datatype == sensor_msgs::PointField::FLOAT64);
    }
  }
  if (height > 1) {
    cloud.width = msg.width;
    cloud.height = msg.height;
  }
  return cloud;
}

class RosbagSource : public ScanSource {
 public:
  RosbagSource(const std::string& path, const DatasetOptions& options)
      : path_(path), frame_(withoutLeadingSlash(options.frame)) {
    if (frame_.empty()) fail(path_, "empty fixed frame (DatasetOptions::frame)");
    try {
      bag_.open(path_, rosbag::bagmode::Read);
    } catch (const rosbag::BagUnindexedException&) {
      fail(path_, "the bag is not indexed (recording interrupted?); run 'rosbag reindex' first");
    } catch (const ros::Exception& e) {
      fail(path_, std::string("cannot open the bag: ") + e.what());
    }
    try {
      chooseTopic(options.topic);
      loadTransforms();
      view_ = std::make_unique<rosbag::View>(bag_, rosbag::TopicQuery(topic_));
      total_ = view_->size();
      it_ = view_->begin();
    } catch (const ros::Exception& e) {
      fail(path_, std::string("cannot read the bag: ") + e.what());
    }
  }

  bool next(Scan& scan) override {
    try {
      while (it_ != view_->end()) {
        const rosbag::MessageInstance& message = *it_;
        const std::string where = path_ + " " + topic_ + " message " + std::to_string(index_);
        ++index_;
        sensor_msgs::PointCloud2::ConstPtr msg = message.instantiate<sensor_msgs::PointCloud2>();
        ++it_;
        if (!msg) throw IoError(where + ": not a sensor_msgs/PointCloud2");
        const std::string cloud_frame = withoutLeadingSlash(msg->header.frame_id);
        Eigen::Isometry3d T_frame_cloud = Eigen::Isometry3d::Identity();
        if (cloud_frame != frame_) {
          if (cloud_frame.empty()) {
            skip(where + ": the cloud has no frame_id");
            continue;
          }
          try {
            T_frame_cloud =
                toIsometry(tf_->lookupTransform(frame_, cloud_frame, msg->header.stamp).transform);
          } catch (const tf2::TransformException& e) {
            skip(where + " (stamp " + std::to_string(msg->header.stamp.toSec()) + "): " + e.what());
            continue;
          }
        }
        scan.cloud = cloudFromMessage(*msg, where);
        scan.T_map_sensor = T_frame_cloud;
        scan.stamp_ns = static_cast<int64_t>(msg->header.stamp.toNSec());
        scan.source = where;
        ++delivered_;
        return true;
      }
    } catch (const ros::Exception& e) {
      fail(path_, std::string("cannot read the bag: ") + e.what());
    }
    if (delivered_ == 0 && skipped_ > 0)
      fail(path_, "none of the " + std::to_string(skipped_) + " clouds on " + topic_ +
                      " could be placed in frame '" + frame_ + "' (last: " + last_skip_reason_ +
                      ")");
    return false;
  }

  std::optional<size_t> size() const override { return total_; }
  std::string describe() const override {
    return "ROS bag " + path_ + ", topic " + topic_ + " (" + std::to_string(total_) +
           " clouds), poses in frame '" + frame_ + "' from " + std::to_string(tf_messages_) +
           " tf messages";
  }
  size_t skipped() const override { return skipped_; }
  std::string lastSkipReason() const override { return last_skip_reason_; }

 private:
  void chooseTopic(const std::string& requested) {
    std::set<std::string> clouds;
    std::map<std::string, std::string> types;
    rosbag::View all(bag_);
    for (const rosbag::ConnectionInfo* connection : all.getConnections()) {
      types[connection->topic] = connection->datatype;
      if (connection->datatype == kPointCloud2Type) clouds.insert(connection->topic);
    }
    if (!requested.empty()) {
      // Accept the topic with or without its leading slash.
      std::string topic = requested;
      if (!types.count(topic) && types.count("/" + topic)) topic = "/" + topic;
      const auto type = types.find(topic);
      if (type == types.end())
        fail(path_, "no topic " + requested +
                        " in the bag (PointCloud2 topics: " + joinTopics(clouds) + ")");
      if (type->second != kPointCloud2Type)
        fail(path_, "topic " + topic + " has type " + type->second + ", not " + kPointCloud2Type +
                        " (PointCloud2 topics: " + joinTopics(clouds) + ")");
      topic_ = topic;
      return;
    }
    if (clouds.empty()) fail(path_, "the bag has no sensor_msgs/PointCloud2 topic");
    if (clouds.size() > 1)
      fail(path_, "the bag has " + std::to_string(clouds.size()) +
                      " PointCloud2 topics, choose one (--topic): " + joinTopics(clouds));
    topic_ = *clouds.begin();
  }

  // Reads every /tf and /tf_static message once, with a cache long enough for the whole bag.
  void loadTransforms() {
    rosbag::View tf_view(bag_, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}));
    const ros::Duration span =
        tf_view.size() > 0 ? tf_view.getEndTime() - tf_view.getBeginTime() : ros::Duration(0);
    rosbag::View whole(bag_);
    const ros::Duration bag_span =
        whole.size() > 0 ? whole.getEndTime() - whole.getBeginTime() : ros::Duration(0);
    tf_ = std::make_unique<tf2::BufferCore>(std::max(span, bag_span) + ros::Duration(60.0));
    for (const rosbag::MessageInstance& message : tf_view) {
      const tf2_msgs::TFMessage::ConstPtr msg = message.instantiate<tf2_msgs::TFMessage>();
      if (!msg) continue;  // another type on a tf topic: not ours to interpret
      const bool is_static = message.getTopic() == "/tf_static";
      for (const geometry_msgs::TransformStamped& transform : msg->transforms)
        tf_->setTransform(transform, "bag", is_static);
      ++tf_messages_;
    }
  }

  void skip(const std::string& reason) {
    ++skipped_;
    last_skip_reason_ = reason;
  }

  std::string path_;
  std::string frame_;
  std::string topic_;
  rosbag::Bag bag_;
  std::unique_ptr<tf2::BufferCore> tf_;
  std::unique_ptr<rosbag::View> view_;
  rosbag::View::iterator it_;
  size_t total_ = 0;
  size_t index_ = 0;
  size_t delivered_ = 0;
  size_t skipped_ = 0;
  size_t tf_messages_ = 0;
  std::string last_skip_reason_;
};

}  // namespace

std::unique_ptr<ScanSource> openRosbag(const std::string& path, const DatasetOptions& options) {
  return std::make_unique<RosbagSource>(path, options);
}

void registerRosbagReader() { registerBagOpener(openRosbag); }

}  // namespace fragg
