#include "relaxed_connectivity/ros/haptic_driver.h"

#include <diagnostic_msgs/DiagnosticStatus.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <relaxed_connectivity/HapticButtons.h>
#include <relaxed_connectivity/HapticLoopStats.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/brush_skeleton.h"
#include "relaxed_connectivity/ros/marker_haptic_device.h"
#include "relaxed_connectivity/ros/replay_haptic_device.h"

namespace rc {
namespace {

constexpr size_t kRingSize = 1024;  // ticks the publisher may fall behind (1 s at 1 kHz)

std::unique_ptr<HapticDevice> makeDevice(const HapticDriverParams& p, const ros::NodeHandle& private_nh,
                                         const BrushPreset& brush) {
  if (p.device == "replay") return std::make_unique<ReplayHapticDevice>(p.stroke, p.real_time);
  if (p.device == "marker")
    return std::make_unique<MarkerHapticDevice>(private_nh.resolveName("marker"), p.base_frame,
                                                Vec3(0, 0, 2 * brush.bristle_length), brush.bristle_length);
  return std::make_unique<HeldPoseDevice>();  // topic
}

FixedRateLoopOptions loopOptions(const HapticDriverParams& p, const HapticDevice& device) {
  FixedRateLoopOptions o;
  o.rate = p.rate;
  o.paced = device.paced();
  o.stats_window = int(std::ceil(p.rate * p.stats_period)) + 1;
  o.realtime_priority = p.realtime_priority;
  return o;
}

BrushPreset readBrush(const HapticDriverParams& p) {
  return readBrushPreset(p.brush);
}

}  // namespace

void HapticDriverParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("haptic_driver: " + what); };
  if (device != "replay" && device != "marker" && device != "topic")
    fail("device '" + device + "' is none of replay, marker, topic");
  if (device_name.empty()) fail("device_name must not be empty");
  if (brush.empty()) fail("~brush (a brush preset file, e.g. config/paint/brushes/round.yaml) is required");
  if (device == "replay" && stroke.empty()) fail("device replay needs ~stroke (a stroke file)");
  if (!(rate > 0) || !std::isfinite(rate)) fail("rate must be > 0 Hz (got " + std::to_string(rate) + ")");
  if (!(filter_window > 0) || !std::isfinite(filter_window))
    fail("filter_window must be > 0 s (got " + std::to_string(filter_window) + ")");
  if (!(stats_period > 0)) fail("stats_period must be > 0 s");
  if (!(start_delay >= 0) || !std::isfinite(start_delay))
    fail("start_delay must be >= 0 s (got " + std::to_string(start_delay) + ")");
  if (base_frame.empty() || world_frame.empty() || base_frame == world_frame)
    fail("base_frame and world_frame must be two different non-empty frames");
  if (base_pose.size() != 6) fail("base_pose must be [x, y, z, roll, pitch, yaw]");
  try {
    law.validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

HapticDriverParams readHapticDriverParams(const ros::NodeHandle& pnh) {
  HapticDriverParams p;
  pnh.param("device", p.device, p.device);
  pnh.param("device_name", p.device_name, p.device_name);
  pnh.param("brush", p.brush, p.brush);
  pnh.param("stroke", p.stroke, p.stroke);
  pnh.param("real_time", p.real_time, p.real_time);
  pnh.param("rate", p.rate, p.rate);
  pnh.param("filter_window", p.filter_window, p.filter_window);
  std::string depth_mode = "plane";
  pnh.param("depth_mode", depth_mode, depth_mode);
  p.law.depth_mode = parseDepthMode(depth_mode);
  pnh.param("stale_timeout", p.law.stale_timeout, p.law.stale_timeout);
  pnh.param("fade_time", p.law.fade_time, p.law.fade_time);
  pnh.param("add_bristle_force", p.law.add_bristle_force, p.law.add_bristle_force);
  pnh.param("base_frame", p.base_frame, p.base_frame);
  pnh.param("world_frame", p.world_frame, p.world_frame);
  pnh.param("base_pose", p.base_pose, p.base_pose);
  pnh.param("realtime_priority", p.realtime_priority, p.realtime_priority);
  pnh.param("stats_period", p.stats_period, p.stats_period);
  pnh.param("start_delay", p.start_delay, p.start_delay);
  p.validate();
  return p;
}

HapticDriver::HapticDriver(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : HapticDriver(nh, private_nh, readHapticDriverParams(private_nh)) {}

HapticDriver::HapticDriver(ros::NodeHandle nh, ros::NodeHandle private_nh, HapticDriverParams params)
    : HapticDriver(nh, private_nh, params, readBrush(params)) {}

HapticDriver::HapticDriver(ros::NodeHandle nh, ros::NodeHandle private_nh, HapticDriverParams params,
                           const BrushPreset& brush)
    : nh_(nh),
      private_nh_(private_nh),
      params_(std::move(params)),
      device_(makeDevice(params_, private_nh_, brush)),
      law_(BrushSkeleton(brush).handleOffsets(), params_.law),
      low_pass_(params_.filter_window, int(std::ceil(params_.filter_window * params_.rate)) + 64),
      diagnostics_(nh, private_nh, "haptic_driver"),
      ring_(kRingSize),
      loop_(loopOptions(params_, *device_)) {
  pending_contact_.handles.reserve(size_t(law_.handleCount()));
  if (params_.device == "topic") held_device_ = static_cast<HeldPoseDevice*>(device_.get());
  const std::string& d = params_.device_name;
  const ros::TransportHints no_delay = ros::TransportHints().tcpNoDelay();
  // An unpaced replay publishes its ticks in a burst: an unbounded outgoing queue (0) keeps every one.
  const uint32_t queue = device_->paced() ? 100 : 0;
  force_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>(d + "/force_feedback", queue);
  stats_pub_ = nh_.advertise<relaxed_connectivity::HapticLoopStats>(d + "/stats", 10);
  if (device_->publishesPose()) {
    pose_pub_ = nh_.advertise<geometry_msgs::PoseStamped>(d + "/pose", queue);
    button_pub_ = nh_.advertise<relaxed_connectivity::HapticButtons>(d + "/button", 10, /*latch=*/true);
  } else {
    pose_sub_ = nh_.subscribe(d + "/pose", 100, &HapticDriver::poseCallback, this, no_delay);
  }
  contact_sub_ = nh_.subscribe("brush_contact", 10, &HapticDriver::contactCallback, this, no_delay);
  diagnostics_.addTask("force loop",
                       [this](diagnostic_updater::DiagnosticStatusWrapper& s) { reportLoop(s); });
  if (pose_sub_) diagnostics_.addInput(pose_sub_.getTopic(), 1.0);
  diagnostics_.addInput(contact_sub_.getTopic(), 5.0);

  geometry_msgs::TransformStamped base;
  base.header.stamp = ros::Time::now();
  base.header.frame_id = params_.world_frame;
  base.child_frame_id = params_.base_frame;
  const std::vector<double>& b = params_.base_pose;
  base.transform.translation.x = b[0];
  base.transform.translation.y = b[1];
  base.transform.translation.z = b[2];
  const Eigen::Quaterniond q = Eigen::AngleAxisd(b[5], Vec3::UnitZ()) *
                               Eigen::AngleAxisd(b[4], Vec3::UnitY()) *
                               Eigen::AngleAxisd(b[3], Vec3::UnitX());
  base.transform.rotation.x = q.x();
  base.transform.rotation.y = q.y();
  base.transform.rotation.z = q.z();
  base.transform.rotation.w = q.w();
  static_tf_.sendTransform(base);

  publisher_ = std::thread([this] { publishLoop(); });
  if (params_.start_delay > 0)
    start_timer_ = nh_.createWallTimer(
        ros::WallDuration(params_.start_delay), [this](const ros::WallTimerEvent&) { startLoop(); }, true);
  else
    startLoop();
  ROS_INFO_STREAM("haptic_driver: device "
                  << params_.device << " ('" << d << "'), brush " << brush.name << " (" << law_.handleCount()
                  << " handle points), " << params_.rate << " Hz force loop"
                  << (loop_.options().paced ? "" : " (unpaced)") << ", depth "
                  << (params_.law.depth_mode == DepthMode::kPlane ? "plane" : "constant"));
}

HapticDriver::~HapticDriver() {
  {
    std::lock_guard<std::mutex> lock(ring_mutex_);
    stopping_ = true;  // first: an unpaced loop may be waiting for room in the ring
  }
  ring_not_full_.notify_all();
  loop_.stop();
  ring_not_empty_.notify_all();
  if (publisher_.joinable()) publisher_.join();
}

void HapticDriver::startLoop() {
  start_stamp_ = ros::Time::now();  // read by the publisher thread only after the first tick (ring mutex)
  loop_.start([this](uint64_t k, double t) { return tick(k, t); });
}

void HapticDriver::poseCallback(const geometry_msgs::PoseStampedConstPtr& msg) {
  const auto& p = msg->pose.position;
  const auto& q = msg->pose.orientation;
  const Vec3 position(p.x, p.y, p.z);
  const Eigen::Quaterniond orientation(q.w, q.x, q.y, q.z);
  std::string problem;
  if (!msg->header.frame_id.empty() && msg->header.frame_id != params_.base_frame)
    problem = "frame '" + msg->header.frame_id + "' is not " + params_.base_frame;
  else if (const PoseProblem bad = checkDevicePose(position, orientation); bad != PoseProblem::kNone)
    problem = poseProblemName(bad);
  if (!problem.empty()) {
    ++dropped_poses_;
    ROS_WARN_STREAM_THROTTLE(
        1.0, "haptic_driver: dropped pose (" << problem << "), " << dropped_poses_.load() << " so far");
    diagnostics_.rejected(pose_sub_.getTopic(), problem);
    return;
  }
  diagnostics_.accepted(pose_sub_.getTopic());
  // Seconds since the first pose: epoch seconds in a double resolve only ~240 ns, 2.4e-4 of a 1 ms pose
  // interval.
  if (stamp_origin_.isZero()) stamp_origin_ = msg->header.stamp;
  if (held_device_) held_device_->setPose((msg->header.stamp - stamp_origin_).toSec(), position, orientation);
}

void HapticDriver::contactCallback(const relaxed_connectivity::BrushContactConstPtr& msg) {
  ContactParameters c;
  c.penalty_stiffness = msg->penalty_stiffness;
  c.friction = msg->friction;
  c.bristle_force = Vec3(msg->bristle_force.x, msg->bristle_force.y, msg->bristle_force.z);
  for (const auto& h : msg->handles) {
    HandleContactState s;
    s.index = h.index > uint32_t(INT32_MAX) ? -1 : int(h.index);
    s.depth = h.depth;
    s.normal = Vec3(h.normal.x, h.normal.y, h.normal.z);
    s.position = Vec3(h.position.x, h.position.y, h.position.z);
    c.handles.push_back(s);
  }
  std::string problem;
  if (!msg->header.frame_id.empty() && msg->header.frame_id != params_.base_frame)
    problem = "frame '" + msg->header.frame_id + "' is not " + params_.base_frame;
  else if (const ContactProblem bad = law_.check(c); bad != ContactProblem::kNone)
    problem = contactProblemName(bad);
  if (!problem.empty()) {
    ++dropped_contacts_;
    ROS_WARN_STREAM_THROTTLE(1.0, "haptic_driver: dropped brush contact ("
                                      << problem << "), " << dropped_contacts_.load() << " so far");
    diagnostics_.rejected(contact_sub_.getTopic(), problem);
    return;
  }
  diagnostics_.accepted(contact_sub_.getTopic());
  std::lock_guard<std::mutex> lock(contact_mutex_);
  pending_contact_ = c;
  contact_pending_ = true;
}

bool HapticDriver::tick(uint64_t, double t) {
  {
    std::lock_guard<std::mutex> lock(contact_mutex_);
    if (contact_pending_) {
      law_.setContact(pending_contact_, t);
      contact_pending_ = false;
    }
  }
  TickOutput out;
  out.t = t;
  out.has_pose = device_->sample(t, out.device, out.buttons);
  const HapticForce force = out.has_pose ? law_.evaluate(out.device, t) : HapticForce{};
  low_pass_.add(t, force.wrench);
  out.wrench = low_pass_.value(t);
  out.contact_age = law_.contactAge(t);
  out.fade = force.fade;
  device_->command(out.wrench);
  {
    std::unique_lock<std::mutex> lock(ring_mutex_);
    if (ring_count_ == ring_.size()) {
      if (loop_.options().paced) {  // never block a paced loop: lose the oldest output
        ring_head_ = (ring_head_ + 1) % ring_.size();
        --ring_count_;
        ++unpublished_ticks_;
      } else {
        ring_not_full_.wait(lock, [this] { return stopping_ || ring_count_ < ring_.size(); });
        if (stopping_) return false;
      }
    }
    ring_[(ring_head_ + ring_count_) % ring_.size()] = out;
    ++ring_count_;
  }
  ring_not_empty_.notify_one();
  return !device_->finished(t);
}

void HapticDriver::publishLoop() {
  geometry_msgs::WrenchStamped force;
  force.header.frame_id = params_.base_frame;
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = params_.base_frame;
  relaxed_connectivity::HapticButtons buttons;
  buttons.header.frame_id = params_.base_frame;
  bool buttons_sent = false;
  uint32_t last_buttons = 0;
  double next_stats = params_.stats_period;
  std::vector<TickOutput> batch;
  batch.reserve(kRingSize);
  while (true) {
    {
      std::unique_lock<std::mutex> lock(ring_mutex_);
      ring_not_empty_.wait(lock, [this] { return stopping_ || ring_count_ > 0; });
      if (stopping_ && ring_count_ == 0) return;
      batch.clear();
      for (; ring_count_ > 0; --ring_count_, ring_head_ = (ring_head_ + 1) % ring_.size())
        batch.push_back(ring_[ring_head_]);
    }
    ring_not_full_.notify_one();
    for (const TickOutput& o : batch) {
      const ros::Time stamp = start_stamp_ + ros::Duration(o.t);
      if (o.has_pose && device_->publishesPose()) {
        pose.header.stamp = stamp;
        pose.pose.position.x = o.device.pose.translation().x();
        pose.pose.position.y = o.device.pose.translation().y();
        pose.pose.position.z = o.device.pose.translation().z();
        const Eigen::Quaterniond q(o.device.pose.linear());
        pose.pose.orientation.x = q.x();
        pose.pose.orientation.y = q.y();
        pose.pose.orientation.z = q.z();
        pose.pose.orientation.w = q.w();
        pose_pub_.publish(pose);
        if (!buttons_sent || o.buttons != last_buttons) {
          buttons.header.stamp = stamp;
          buttons.pressed.assign(2, false);
          for (size_t i = 0; i < buttons.pressed.size(); ++i) buttons.pressed[i] = (o.buttons >> i) & 1u;
          button_pub_.publish(buttons);
          buttons_sent = true;
          last_buttons = o.buttons;
        }
      }
      force.header.stamp = stamp;
      force.wrench.force.x = o.wrench[0];
      force.wrench.force.y = o.wrench[1];
      force.wrench.force.z = o.wrench[2];
      force.wrench.torque.x = o.wrench[3];
      force.wrench.torque.y = o.wrench[4];
      force.wrench.torque.z = o.wrench[5];
      force_pub_.publish(force);
      if (o.t >= next_stats) {
        publishStats(o);
        next_stats +=
            params_.stats_period * std::max(1.0, std::floor((o.t - next_stats) / params_.stats_period));
      }
    }
  }
}

void HapticDriver::publishStats(const TickOutput& last) {
  const LoopTimingSummary s = loop_.summary(/*clear_window=*/true);
  relaxed_connectivity::HapticLoopStats stats;
  stats.header.stamp = start_stamp_ + ros::Duration(last.t);
  stats.header.frame_id = params_.base_frame;
  stats.rate = params_.rate;
  stats.ticks = s.ticks;
  stats.missed_ticks = s.missed_ticks;
  stats.period_p50 = s.period_p50;
  stats.period_p99 = s.period_p99;
  stats.period_max = s.period_max;
  stats.jitter_p50 = s.jitter_p50;
  stats.jitter_p99 = s.jitter_p99;
  stats.jitter_max = s.jitter_max;
  stats.dropped_poses = dropped_poses_;
  stats.dropped_contacts = dropped_contacts_;
  stats.contact_stale = last.contact_age > params_.law.stale_timeout;
  stats.contact_age = std::isfinite(last.contact_age) ? last.contact_age : -1.0;
  stats.force_norm = last.wrench.head<3>().norm();
  {
    std::lock_guard<std::mutex> lock(ring_mutex_);
    stats.unpublished_ticks = unpublished_ticks_;
  }
  stats_pub_.publish(stats);
  std::lock_guard<std::mutex> lock(stats_mutex_);
  last_stats_ = stats;
}

void HapticDriver::reportLoop(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  const relaxed_connectivity::HapticLoopStats& s = last_stats_;
  status.add("rate [Hz]", s.rate);
  status.add("ticks", s.ticks);
  status.add("missed ticks", s.missed_ticks);
  status.add("jitter p99 [ms]", 1e3 * s.jitter_p99);
  status.add("jitter max [ms]", 1e3 * s.jitter_max);
  status.add("dropped poses", s.dropped_poses);
  status.add("dropped contacts", s.dropped_contacts);
  status.add("contact stale", s.contact_stale);
  const uint64_t missed = s.missed_ticks - std::min(s.missed_ticks, reported_missed_ticks_);
  reported_missed_ticks_ = s.missed_ticks;
  const double bound = 0.2 / s.rate;  // a fifth of the period (0.2 ms at 1 kHz)
  if (s.ticks == 0)
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "starting");
  else if (missed > 0)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "%llu ticks missed since the last report",
                    static_cast<unsigned long long>(missed));
  else if (s.jitter_p99 > bound)
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN, "jitter p99 %.3f ms above %.3f ms",
                    1e3 * s.jitter_p99, 1e3 * bound);
  else
    status.summaryf(diagnostic_msgs::DiagnosticStatus::OK, "%.0f Hz, jitter p99 %.3f ms", s.rate,
                    1e3 * s.jitter_p99);
}

}  // namespace rc
