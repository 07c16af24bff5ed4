// A PointCloud2 input through a tf2_ros::MessageFilter whose wait is bounded (issue 24). The filter holds a
// cloud until the transform of its stamp is known and drops it only when newer tf data has passed it or its
// queue overflows: without tf traffic, a cloud of an unknown frame waited forever, unreported. Here a cloud
// that waited longer than max_wait seconds (wall time) is refused through `refused` with the reason; the
// filter's own failures go to `failed`, passed clouds to `ready`.
#pragma once

#include <message_filters/subscriber.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace rc {

class BoundedTfFilter {
 public:
  using Cloud = sensor_msgs::PointCloud2ConstPtr;
  using Ready = std::function<void(const Cloud&)>;
  using Failed = std::function<void(const Cloud&, tf2_ros::filter_failure_reasons::FilterFailureReason)>;
  using Refused = std::function<void(const Cloud&, const std::string& reason)>;

  /// Subscribes to `topic` (queue `subscriber_queue`) through a filter to `target_frame` holding at most
  /// `filter_queue` clouds; checks the waits 4 times a second. max_wait > 0.
  BoundedTfFilter(ros::NodeHandle nh, const std::string& topic, uint32_t subscriber_queue,
                  tf2_ros::Buffer& tf, const std::string& target_frame, uint32_t filter_queue,
                  double max_wait, Ready ready, Failed failed, Refused refused);

  const std::string& topic() const { return topic_; }

 private:
  void left(const Cloud& msg);
  void refuseStale();

  std::string topic_, target_frame_;
  double max_wait_;
  Refused refused_;
  message_filters::Subscriber<sensor_msgs::PointCloud2> subscriber_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>> filter_;
  std::mutex mutex_;
  std::vector<std::pair<Cloud, ros::WallTime>> waiting_;  // in the filter since
  ros::WallTimer timer_;
};

}  // namespace rc
