#include "relaxed_connectivity/ros/bounded_tf_filter.h"

#include <algorithm>
#include <cstdio>
#include <stdexcept>

namespace rc {

BoundedTfFilter::BoundedTfFilter(ros::NodeHandle nh, const std::string& topic, uint32_t subscriber_queue,
                                 tf2_ros::Buffer& tf, const std::string& target_frame, uint32_t filter_queue,
                                 double max_wait, Ready ready, Failed failed, Refused refused)
    : topic_(topic), target_frame_(target_frame), max_wait_(max_wait), refused_(std::move(refused)) {
  if (!(max_wait > 0.0)) throw std::invalid_argument("BoundedTfFilter: max_wait must be positive");
  subscriber_.subscribe(nh, topic, subscriber_queue);
  // Registered before the filter connects: a cloud is noted as waiting before the filter can pass it on.
  subscriber_.registerCallback([this](const Cloud& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    waiting_.emplace_back(msg, ros::WallTime::now());
  });
  filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::PointCloud2>>(subscriber_, tf, target_frame,
                                                                               filter_queue, nh);
  filter_->registerCallback([this, ready = std::move(ready)](const Cloud& msg) {
    left(msg);
    ready(msg);
  });
  filter_->registerFailureCallback(
      [this, failed = std::move(failed)](const Cloud& msg,
                                         tf2_ros::filter_failure_reasons::FilterFailureReason why) {
        left(msg);
        failed(msg, why);
      });
  timer_ = nh.createWallTimer(ros::WallDuration(0.25), [this](const ros::WallTimerEvent&) { refuseStale(); });
}

void BoundedTfFilter::left(const Cloud& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  waiting_.erase(
      std::remove_if(waiting_.begin(), waiting_.end(), [&](const auto& w) { return w.first == msg; }),
      waiting_.end());
}

void BoundedTfFilter::refuseStale() {
  std::vector<Cloud> refused;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::WallTime now = ros::WallTime::now();
    if (std::none_of(waiting_.begin(), waiting_.end(),
                     [&](const auto& w) { return (now - w.second).toSec() > max_wait_; }))
      return;
    filter_->clear();  // (the filter can only be emptied as a whole: every cloud in it is refused)
    for (const auto& w : waiting_) refused.push_back(w.first);
    waiting_.clear();
  }
  char wait[32];
  std::snprintf(wait, sizeof(wait), "%g", max_wait_);
  for (const Cloud& msg : refused)
    refused_(msg, "no transform of frame '" + msg->header.frame_id + "' to '" + target_frame_ + "' within " +
                      wait + " s");
}

}  // namespace rc
