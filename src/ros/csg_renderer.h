// The csg_renderer node/nodelet (one class behind a node main and a nodelet): renders CSG combinations of
// surfel patches (thesis 4.2) with the EWA splatting renderer, from a camera that tf places, and publishes
// the images.
//
// Subscribes  surfels (sensor_msgs/PointCloud2 with a `patch_id` field, any frame with a tf2 path to
//             fixed_frame) and each topic of ~patch_topics (patch id = index in the list; no patch_id field
//             needed). The latest cloud of every topic is kept; they are merged for rendering.
// Publishes   ~image (sensor_msgs/Image rgb8), ~depth (32FC1, metres, NaN background), ~patch_id (32SC1, -1
//             background), ~camera_info (all latched, header frame = camera_frame, stamp = latest cloud/tf
//             stamp), ~stats (relaxed_connectivity/CsgRenderStats, one per rendered frame).
// Services    ~set_csg_tree (relaxed_connectivity/SetCsgTree): a bad expression is rejected with the parser's
//             message and the previous tree is kept; dynamic_reconfigure (~set_parameters,
//             config/dynamic_reconfigure/Splat.cfg): the splat settings, applied from the next frame.
// Parameters  (private) fixed_frame, camera_frame, csg, patch_topics, use_surfels_topic, tf_queue_size,
// tf_wait,
//             max_rate, width, height, horizontal_fov (degrees), fx fy cx cy (override the fov when fx > 0),
//             orthographic, ortho_view_width, near_clip, far_clip, pose_tolerance, partner_method,
//             ewa_filter, lowpass_variance, cutoff_radius, depth_tolerance_scale, exact_footprint,
//             exact_silhouettes, shading, backface_culling (leave off for CSG: cavity walls are back
//             faces), background [r g b], threads; see config/csg_demo.yaml.
//
// A frame is rendered only when something changed (a new cloud, a new tree, the camera moved by more than
// pose_tolerance), at most max_rate times per second. Bad input (malformed cloud, missing patch_id, normals
// or radii, NaNs, bad expression, unknown camera transform) is logged and rejected; the last good state
// stays.
#pragma once

#include <dynamic_reconfigure/server.h>
#include <relaxed_connectivity/CsgRenderStats.h>
#include <relaxed_connectivity/SetCsgTree.h>
#include <relaxed_connectivity/SplatConfig.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "relaxed_connectivity/core/surfel_cloud.h"
#include "relaxed_connectivity/render/csg/csg_tree.h"
#include "relaxed_connectivity/render/csg/patch_cloud_set.h"
#include "relaxed_connectivity/render/splat/camera.h"
#include "relaxed_connectivity/render/splat/surfel_renderer.h"
#include "relaxed_connectivity/ros/bounded_tf_filter.h"
#include "relaxed_connectivity/ros/node_diagnostics.h"

namespace rc {

class CsgClipper;

struct CsgRendererParams {
  std::string fixed_frame = "world";
  std::string camera_frame = "csg_camera";  ///< optical convention (REP 103): z forward, x right, y down
  std::string csg;                          ///< initial CSG expression; empty: all patches, unclipped
  std::vector<std::string> patch_topics;    ///< patch i comes from topic i
  bool use_surfels_topic = true;            ///< subscribe to `surfels` (clouds with a patch_id field)
  /// Clouds of each input waiting for the transform of their stamp (tf2_ros::MessageFilter); one pushed out
  /// still without it is rejected naming its frame.
  int tf_queue_size = 5;
  /// Seconds a cloud waits for its transform before it is rejected (without tf traffic the filter alone would
  /// hold a cloud of an unknown frame forever).
  double tf_wait = 30.0;
  double max_rate = 10.0;        ///< frames per second at most
  double pose_tolerance = 1e-6;  ///< camera motion (metres / radians) that triggers a new frame
  std::string partner_method =
      "spatial_index";  ///< spatial_index (faster, bench_clip_partners) | clip_buffer (Algorithm 4.1)
  // Intrinsics
  int width = 640, height = 480;
  double horizontal_fov = 60.0;             ///< degrees
  double fx = 0, fy = 0, cx = -1, cy = -1;  ///< fx > 0 overrides the fov; cx, cy < 0: image centre
  bool orthographic = false;
  double ortho_view_width = 2.0;  ///< metres across the image (orthographic)
  double near_clip = 0.01, far_clip = 100.0;
  SplatConfig splat;

  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
  /// The camera of these intrinsics (pose identity).
  Camera camera() const;
};

/// Reads the private parameters once (defaults: CsgRendererParams{}) and validates them (throws
/// std::invalid_argument, also for a `csg` that does not parse).
CsgRendererParams readCsgRendererParams(const ros::NodeHandle& private_nh);

class CsgRenderer {
 public:
  /// Reads and validates the parameters (throws std::invalid_argument), then subscribes and advertises.
  CsgRenderer(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~CsgRenderer();

  /// `surfels`: clouds whose patch_id field names the patch of every surfel.
  void surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  /// ~patch_topics[patch]: one patch per topic.
  void patchCallback(int patch, const sensor_msgs::PointCloud2ConstPtr& msg);
  bool setCsgTree(relaxed_connectivity::SetCsgTree::Request& request,
                  relaxed_connectivity::SetCsgTree::Response& response);
  /// dynamic_reconfigure (config/dynamic_reconfigure/Splat.cfg): new splat settings for the next frame (a
  /// re-render); settings the renderer refuses (back-face culling with a difference in the tree) are put
  /// back in `config`, which the reconfigure service answers with.
  void reconfigure(relaxed_connectivity::SplatConfig& config, uint32_t level);
  /// Looks up the camera, and renders and publishes a frame if anything changed. Returns true if it did.
  bool renderIfChanged();

  const CsgRendererParams& params() const { return params_; }

 private:
  struct Source {  // the latest accepted cloud of one input topic, in fixed_frame
    std::shared_ptr<const SurfelCloud> cloud;
    ros::Time stamp;
  };
  void acceptCloud(size_t source, int patch, const sensor_msgs::PointCloud2ConstPtr& msg);
  void reject(const std::string& what, const std::string& reason);
  void timerCallback(const ros::WallTimerEvent&);
  void renderBackground(const Camera& camera);

  ros::NodeHandle nh_, private_nh_;
  CsgRendererParams params_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;
  ros::Publisher image_pub_, depth_pub_, patch_pub_, info_pub_, stats_pub_;
  ros::ServiceServer set_tree_srv_;
  ros::WallTimer timer_;
  SurfelRenderer renderer_;
  NodeDiagnostics diagnostics_;  // per input topic: rate, accepted, rejected

  std::mutex mutex_;  // guards the input state below (nodelet managers call back from several threads)
  std::vector<Source> sources_;  // [0]: `surfels`, [1 + i]: patch_topics[i]
  std::string expression_;       // the accepted CSG expression ("" : no clipping)
  std::optional<CsgTree> tree_;
  bool inputs_changed_ = true;  // a cloud or the tree changed since the last frame
  uint32_t rejected_inputs_ = 0;
  std::string last_error_;
  std::optional<SplatConfig> pending_splat_;  // from reconfigure(), taken by the next frame

  // Render state (timer thread only)
  std::unique_ptr<PatchCloudSet> patches_;  // merged inputs of the tree's patches and their clipper
  std::optional<Eigen::Isometry3d> last_pose_;
  RenderImages images_;
  uint32_t rendered_frames_ = 0;

  // ~set_parameters etc. (dynamic_reconfigure), started after everything it touches.
  std::unique_ptr<dynamic_reconfigure::Server<relaxed_connectivity::SplatConfig>> reconfigure_server_;
  // The inputs (`surfels`, then the patch topics), each through a tf2_ros::MessageFilter to fixed_frame
  // (last: stopped first).
  std::vector<std::unique_ptr<BoundedTfFilter>> inputs_;
};

}  // namespace rc
