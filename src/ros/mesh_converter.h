// The mesh_converter node/nodelet (one class behind both, like octomap_server): surfels -> a simplified mesh
// with colour and normal texture atlases (thesis 6, src/convert/), as an action so that a long conversion
// reports its stage and can be cancelled, and as a latched Marker for rviz.
//
// Subscribes  surfels (sensor_msgs/PointCloud2 with normals; kept, not converted, until a goal asks with
//             use_latest: remap it to the painted object, e.g. /surfels/painted)
// Publishes   ~converted (visualization_msgs/Marker TRIANGLE_LIST, latched: the last result in the cloud's
//             frame, each corner coloured from the texture at it)
// Actions     ~convert (relaxed_connectivity/ConvertSurfels: goal = a cloud, a file or the latest cloud, and
//             the two error parameters; feedback = stage and fraction; result = files and measured errors)
// Parameters  (private) output_dir (where goals without output_prefix write; "~/.ros/converted"),
//             write_obj (true), write_glb (true) for goals that set neither, simplify_error (0.0005),
//             target_triangles (0), color_error (0.03), normal_error (0.002), normal_texture (true),
//             depth_error (0.05), depth_texture (false: no displacement texture), border (1),
//             max_page_size (4096), fill_gaps (true: shorter patches fill each row's gaps), reconstruction
//             (advancing_front | scale_space | poisson), require_manifold (true), viewpoint ([x, y, z]:
//             normals of files without them are oriented towards it; []: propagated); see
//             config/convert.yaml.
#pragma once

#include <actionlib/server/simple_action_server.h>
#include <relaxed_connectivity/ConvertSurfelsAction.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <visualization_msgs/Marker.h>

#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "relaxed_connectivity/convert/surfel_conversion.h"
#include "relaxed_connectivity/ros/node_diagnostics.h"

namespace rc {

struct MeshConverterParams {
  std::string output_dir;  ///< "": ~/.ros/converted
  bool write_obj = true, write_glb = true;
  ConversionOptions conversion;
  std::optional<Vec3> viewpoint;
  /// Throws std::invalid_argument naming the parameter and the bad value.
  void validate() const;
};

/// Reads the private parameters once (defaults: MeshConverterParams{}) and validates them.
MeshConverterParams readMeshConverterParams(const ros::NodeHandle& private_nh);

/// A triangle-list Marker of a textured mesh: three points per triangle, each coloured by the texture there.
visualization_msgs::Marker meshMarker(const TexturedMesh& mesh, const std::string& frame_id);

class MeshConverter {
 public:
  /// Reads and validates the parameters (throws std::invalid_argument), then subscribes, advertises and
  /// starts the action server.
  MeshConverter(ros::NodeHandle nh, ros::NodeHandle private_nh);
  const MeshConverterParams& params() const { return params_; }

 private:
  using Server = actionlib::SimpleActionServer<relaxed_connectivity::ConvertSurfelsAction>;
  void surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg);
  void convert(const relaxed_connectivity::ConvertSurfelsGoalConstPtr& goal);
  /// The goal's surfels and frame; throws std::invalid_argument for a goal without usable input.
  SurfelCloud goalSurfels(const relaxed_connectivity::ConvertSurfelsGoal& goal, std::string* frame_id,
                          std::string* name);

  ros::NodeHandle nh_, private_nh_;
  MeshConverterParams params_;
  ros::Subscriber surfels_sub_;
  ros::Publisher marker_pub_;
  std::unique_ptr<Server> server_;
  std::mutex mutex_;  // guards latest_ and the goal counts
  sensor_msgs::PointCloud2ConstPtr latest_;
  unsigned goals_succeeded_ = 0, goals_aborted_ = 0;
  std::string last_abort_;
  NodeDiagnostics diagnostics_;  // the surfels input and the goals on /diagnostics
};

}  // namespace rc
