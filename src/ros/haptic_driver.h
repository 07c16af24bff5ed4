// The haptic_driver node/nodelet (thesis 5.4.2): the device side of a painting session. A 1 kHz force loop on
// its own thread evaluates the haptic force law (5.6), (5.7) with the latest contact parameters from the
// paint model, low-passes it over 1/60 s and sends it to the device; ROS callbacks only hand over poses and
// contacts. Topic names follow omni_common (<device> = ~device_name, default "haptic"): Subscribes
// brush_contact (relaxed_connectivity/BrushContact, frame = base_frame),
//             <device>/pose (geometry_msgs/PoseStamped; device:=topic only)      [TCP_NODELAY]
// Publishes   <device>/force_feedback (geometry_msgs/WrenchStamped, N and N m, base_frame, every tick),
//             <device>/pose and <device>/button (relaxed_connectivity/HapticButtons, on change) for the
//             simulated devices (replay, marker), <device>/stats (relaxed_connectivity/HapticLoopStats, 1
//             Hz), the static tf world_frame -> base_frame, /diagnostics (the loop's timing, the inputs'
//             rates and dropped messages).
// Parameters  (private) device (replay | marker | topic), device_name, brush (preset file, required), stroke
//             (replay), real_time (replay), rate, filter_window, depth_mode (plane | constant),
//             stale_timeout, fade_time, add_bristle_force, base_frame, world_frame, base_pose ([x, y, z,
//             roll, pitch, yaw]), realtime_priority, stats_period, start_delay. See docs/haptic_driver.md.
#pragma once

#include <geometry_msgs/PoseStamped.h>
#include <relaxed_connectivity/BrushContact.h>
#include <relaxed_connectivity/HapticLoopStats.h>
#include <ros/ros.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <atomic>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "relaxed_connectivity/paint/brush_preset.h"
#include "relaxed_connectivity/paint/fixed_rate_loop.h"
#include "relaxed_connectivity/paint/force_low_pass.h"
#include "relaxed_connectivity/paint/haptic_force_law.h"
#include "relaxed_connectivity/ros/haptic_device.h"
#include "relaxed_connectivity/ros/node_diagnostics.h"

namespace rc {

struct HapticDriverParams {
  std::string device = "replay";
  std::string device_name = "haptic";
  std::string brush;   ///< brush preset file (its handle points are the contract of BrushContact indices)
  std::string stroke;  ///< replay: stroke file
  bool real_time = true;
  double rate = 1000;
  double filter_window = 1.0 / 60.0;
  HapticForceLawOptions law;
  std::string base_frame = "haptic_base";
  std::string world_frame = "world";
  std::vector<double> base_pose = {0, 0, 0, 0, 0, 0};  ///< world -> base: x y z [m], roll pitch yaw [rad]
  int realtime_priority = 0;
  double stats_period = 1.0;
  double start_delay =
      0;  ///< [s] before the loop starts (lets subscribers connect, e.g. to an unpaced replay)

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

HapticDriverParams readHapticDriverParams(const ros::NodeHandle& private_nh);

class HapticDriver {
 public:
  /// Reads and validates the parameters, reads the brush preset and the stroke (their errors name
  /// file:line), subscribes, advertises and starts the force loop and the publisher thread.
  HapticDriver(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~HapticDriver();  ///< stops the threads

  void poseCallback(const geometry_msgs::PoseStampedConstPtr& msg);
  void contactCallback(const relaxed_connectivity::BrushContactConstPtr& msg);

 private:
  HapticDriver(ros::NodeHandle nh, ros::NodeHandle private_nh, HapticDriverParams params);
  HapticDriver(ros::NodeHandle nh, ros::NodeHandle private_nh, HapticDriverParams params,
               const BrushPreset& brush);

  /// What one tick hands to the publisher thread (a fixed-size record: the ring never allocates).
  struct TickOutput {
    double t = 0;
    Wrench wrench = Wrench::Zero();
    DeviceState device;
    uint32_t buttons = 0;
    bool has_pose = false;
    double contact_age = 0;
    double fade = 0;
  };

  void startLoop();
  bool tick(uint64_t k, double t);
  void publishLoop();
  void publishStats(const TickOutput& last);
  // /diagnostics: the force loop's timing of the latest stats window (WARN on missed ticks or a p99 jitter
  // above a fifth of the period, the target at 1 kHz) and the dropped input counts.
  void reportLoop(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_, private_nh_;
  HapticDriverParams params_;
  std::unique_ptr<HapticDevice> device_;
  HeldPoseDevice* held_device_ = nullptr;  // device_ when poses come from the pose topic
  ros::Subscriber pose_sub_, contact_sub_;
  ros::WallTimer start_timer_;
  ros::Publisher force_pub_, pose_pub_, button_pub_, stats_pub_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
  ros::Time start_stamp_;
  ros::Time stamp_origin_;  // of the pose stamps (pose callbacks only)

  // Loop-owned state (only the force loop thread touches these after start).
  HapticForceLaw law_;
  ForceLowPass low_pass_;

  // Handed from the contact callback to the loop.
  std::mutex contact_mutex_;
  ContactParameters pending_contact_;
  bool contact_pending_ = false;
  std::atomic<uint64_t> dropped_poses_{0}, dropped_contacts_{0};
  std::mutex stats_mutex_;
  relaxed_connectivity::HapticLoopStats last_stats_;  // of the latest window (stats_mutex_)
  uint64_t reported_missed_ticks_ = 0;                // at the previous diagnostics report
  NodeDiagnostics diagnostics_;

  // The ring of tick outputs between the loop and the publisher thread.
  std::mutex ring_mutex_;
  std::condition_variable ring_not_empty_, ring_not_full_;
  std::vector<TickOutput> ring_;
  size_t ring_head_ = 0, ring_count_ = 0;
  uint64_t unpublished_ticks_ = 0;  // ticks lost because the publisher fell a whole ring behind
  bool stopping_ = false;

  FixedRateLoop loop_;
  std::thread publisher_;
};

}  // namespace rc
