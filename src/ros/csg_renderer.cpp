#include "relaxed_connectivity/ros/csg_renderer.h"

#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "relaxed_connectivity/render/csg/csg_clipper.h"
#include "relaxed_connectivity/render/csg/patch_clouds.h"
#include "relaxed_connectivity/ros/csg_renderer_images.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/ros/splat_params.h"

namespace rc {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

bool finitePositive(double v) {
  return std::isfinite(v) && v > 0;
}

PartnerMethod parsePartnerMethod(const std::string& name) {
  if (name == "clip_buffer") return PartnerMethod::kClipBuffer;
  if (name == "spatial_index") return PartnerMethod::kSpatialIndex;
  throw std::invalid_argument("csg_renderer: partner_method must be clip_buffer or spatial_index (got '" +
                              name + "')");
}

}  // namespace

void CsgRendererParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("csg_renderer: " + what); };
  auto frameOk = [&](const std::string& name, const std::string& frame) {
    if (frame.empty()) fail(name + " must not be empty");
    if (frame[0] == '/') fail(name + " '" + frame + "' must not start with '/'");
  };
  frameOk("fixed_frame", fixed_frame);
  frameOk("camera_frame", camera_frame);
  if (!use_surfels_topic && patch_topics.empty())
    fail("no input: use_surfels_topic is false and patch_topics is empty");
  for (size_t i = 0; i < patch_topics.size(); ++i)
    if (patch_topics[i].empty()) fail("patch_topics[" + std::to_string(i) + "] is empty");
  if (tf_queue_size < 1) fail("tf_queue_size must be >= 1 (got " + std::to_string(tf_queue_size) + ")");
  if (!finitePositive(tf_wait)) fail("tf_wait must be > 0 s (got " + std::to_string(tf_wait) + ")");
  if (!finitePositive(max_rate)) fail("max_rate must be > 0 Hz (got " + std::to_string(max_rate) + ")");
  if (!(pose_tolerance >= 0) || !std::isfinite(pose_tolerance))
    fail("pose_tolerance must be >= 0 (got " + std::to_string(pose_tolerance) + ")");
  parsePartnerMethod(partner_method);
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    fail("width and height must lie in [1, 16384] (got " + std::to_string(width) + " x " +
         std::to_string(height) + ")");
  if (orthographic) {
    if (!finitePositive(ortho_view_width))
      fail("ortho_view_width must be a positive length (got " + std::to_string(ortho_view_width) + ")");
  } else if (fx > 0) {
    if (!finitePositive(fx) || !finitePositive(fy))
      fail("fx and fy must both be positive (got " + std::to_string(fx) + ", " + std::to_string(fy) + ")");
  } else if (!(horizontal_fov > 0 && horizontal_fov < 180)) {
    fail("horizontal_fov must lie in (0, 180) degrees (got " + std::to_string(horizontal_fov) + ")");
  }
  if (!(near_clip > 0) || !(far_clip > near_clip) || !std::isfinite(far_clip))
    fail("need 0 < near_clip < far_clip (got " + std::to_string(near_clip) + ", " + std::to_string(far_clip) +
         ")");
  if (!csg.empty()) CsgTree::parse(csg);  // throws with the column of the problem
  camera().validate();
  SurfelRenderer check(splat);  // validates the splatting configuration
}

Camera CsgRendererParams::camera() const {
  Camera camera;
  if (orthographic) {
    camera = Camera::orthographic(uint32_t(width), uint32_t(height), ortho_view_width);
  } else if (fx > 0) {
    camera.projection = Camera::Projection::kPerspective;
    camera.width = uint32_t(width);
    camera.height = uint32_t(height);
    camera.fx = fx;
    camera.fy = fy;
    camera.cx = 0.5 * (width - 1.0);
    camera.cy = 0.5 * (height - 1.0);
  } else {
    camera = Camera::perspective(uint32_t(width), uint32_t(height), horizontal_fov * M_PI / 180.0);
  }
  if (cx >= 0) camera.cx = cx;
  if (cy >= 0) camera.cy = cy;
  camera.near_clip = near_clip;
  camera.far_clip = far_clip;
  return camera;
}

CsgRendererParams readCsgRendererParams(const ros::NodeHandle& pnh) {
  CsgRendererParams p;
  pnh.param("fixed_frame", p.fixed_frame, p.fixed_frame);
  pnh.param("camera_frame", p.camera_frame, p.camera_frame);
  XmlRpc::XmlRpcValue csg;
  if (pnh.getParam("csg", csg)) {  // a lone patch id ("0") arrives from roslaunch as an int
    if (csg.getType() == XmlRpc::XmlRpcValue::TypeString)
      p.csg = static_cast<std::string>(csg);
    else if (csg.getType() == XmlRpc::XmlRpcValue::TypeInt)
      p.csg = std::to_string(static_cast<int>(csg));
    else
      throw std::invalid_argument("csg_renderer: csg must be a string expression such as \"0 - (1 | 2)\"");
  }
  pnh.param("patch_topics", p.patch_topics, p.patch_topics);
  pnh.param("use_surfels_topic", p.use_surfels_topic, p.use_surfels_topic);
  pnh.param("tf_queue_size", p.tf_queue_size, p.tf_queue_size);
  pnh.param("tf_wait", p.tf_wait, p.tf_wait);
  pnh.param("max_rate", p.max_rate, p.max_rate);
  pnh.param("pose_tolerance", p.pose_tolerance, p.pose_tolerance);
  pnh.param("partner_method", p.partner_method, p.partner_method);
  pnh.param("width", p.width, p.width);
  pnh.param("height", p.height, p.height);
  pnh.param("horizontal_fov", p.horizontal_fov, p.horizontal_fov);
  pnh.param("fx", p.fx, p.fx);
  pnh.param("fy", p.fy, p.fx > 0 ? p.fx : p.fy);
  pnh.param("cx", p.cx, p.cx);
  pnh.param("cy", p.cy, p.cy);
  pnh.param("orthographic", p.orthographic, p.orthographic);
  pnh.param("ortho_view_width", p.ortho_view_width, p.ortho_view_width);
  pnh.param("near_clip", p.near_clip, p.near_clip);
  pnh.param("far_clip", p.far_clip, p.far_clip);
  SplatConfig& s = p.splat;
  s.outputs = kOutputColor | kOutputDepth | kOutputWeight | kOutputPatchId;  // what the node uses
  readSplatParams(pnh, "csg_renderer", &s);
  p.validate();
  if (s.backface_culling && !p.csg.empty() && CsgTree::parse(p.csg).hasComplementedPatches())
    throw std::invalid_argument("csg_renderer: backface_culling with a CSG difference or complement (csg \"" +
                                p.csg + "\") is not supported: render two-sided (backface_culling false)");
  return p;
}

CsgRenderer::CsgRenderer(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readCsgRendererParams(private_nh)),
      tf_listener_(tf_buffer_, nh),
      renderer_(params_.splat),
      diagnostics_(nh, private_nh, "csg_renderer"),
      sources_(1 + params_.patch_topics.size()) {
  if (!params_.csg.empty()) {
    tree_ = CsgTree::parse(params_.csg);
    expression_ = params_.csg;
  }
  image_pub_ = private_nh_.advertise<sensor_msgs::Image>("image", 1, /*latch=*/true);
  depth_pub_ = private_nh_.advertise<sensor_msgs::Image>("depth", 1, /*latch=*/true);
  patch_pub_ = private_nh_.advertise<sensor_msgs::Image>("patch_id", 1, /*latch=*/true);
  info_pub_ = private_nh_.advertise<sensor_msgs::CameraInfo>("camera_info", 1, /*latch=*/true);
  stats_pub_ = private_nh_.advertise<relaxed_connectivity::CsgRenderStats>("stats", 10);
  set_tree_srv_ = private_nh_.advertiseService("set_csg_tree", &CsgRenderer::setCsgTree, this);
  // Each input through a tf2_ros::MessageFilter: a cloud comes on once the transform of its stamp is known
  // (waiting at most tf_wait).
  auto addInput = [this](const std::string& topic, int patch) {
    auto refuse = [this, topic](const sensor_msgs::PointCloud2ConstPtr& msg, const std::string& reason) {
      diagnostics_.rejected(topic, reason);
      reject("cloud on " + topic + " (frame '" + msg->header.frame_id + "', stamp " +
                 std::to_string(msg->header.stamp.toSec()) + ")",
             reason);
    };
    inputs_.push_back(std::make_unique<BoundedTfFilter>(
        nh_, topic, 5, tf_buffer_, params_.fixed_frame, uint32_t(params_.tf_queue_size), params_.tf_wait,
        [this, patch](const sensor_msgs::PointCloud2ConstPtr& msg) {
          if (patch < 0)
            surfelsCallback(msg);
          else
            patchCallback(patch, msg);
        },
        [this, refuse](const sensor_msgs::PointCloud2ConstPtr& msg,
                       tf2_ros::filter_failure_reasons::FilterFailureReason why) {
          refuse(msg, why == tf2_ros::filter_failure_reasons::EmptyFrameID
                          ? std::string("header.frame_id is empty")
                          : "no transform from '" + msg->header.frame_id + "' to '" + params_.fixed_frame +
                                "' in time (tf2_ros::MessageFilter)");
        },
        refuse));
  };
  if (params_.use_surfels_topic) addInput("surfels", -1);
  if (params_.use_surfels_topic) diagnostics_.addInput("surfels", 0.0);  // latched scenes: never stale
  for (const std::string& topic : params_.patch_topics) diagnostics_.addInput(topic, 0.0);
  for (size_t i = 0; i < params_.patch_topics.size(); ++i) addInput(params_.patch_topics[i], int(i));
  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<relaxed_connectivity::SplatConfig>>(private_nh_);
  reconfigure_server_->setCallback(
      [this](relaxed_connectivity::SplatConfig& config, uint32_t level) { reconfigure(config, level); });
  timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / params_.max_rate), &CsgRenderer::timerCallback, this);
  ROS_INFO_STREAM("csg_renderer: " << (params_.use_surfels_topic ? "surfels" : "") << " + "
                                   << params_.patch_topics.size() << " patch topics, camera '"
                                   << params_.camera_frame << "' in '" << params_.fixed_frame << "', "
                                   << params_.width << " x " << params_.height << ", csg \"" << expression_
                                   << "\", at most " << params_.max_rate << " Hz");
}

CsgRenderer::~CsgRenderer() {
  timer_.stop();
}

void CsgRenderer::reject(const std::string& what, const std::string& reason) {
  const std::string text = "rejected " + what + ": " + reason;
  ROS_ERROR_STREAM("csg_renderer: " << text);
  std::lock_guard<std::mutex> lock(mutex_);
  ++rejected_inputs_;
  last_error_ = text;
}

void CsgRenderer::surfelsCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  acceptCloud(0, -1, msg);
}

void CsgRenderer::patchCallback(int patch, const sensor_msgs::PointCloud2ConstPtr& msg) {
  acceptCloud(1 + size_t(patch), patch, msg);
}

void CsgRenderer::acceptCloud(size_t source, int patch, const sensor_msgs::PointCloud2ConstPtr& msg) {
  const std::string what =
      "cloud on " +
      (patch < 0 ? std::string("surfels")
                 : params_.patch_topics[size_t(patch)] + " (patch " + std::to_string(patch) + ")") +
      " (frame '" + msg->header.frame_id + "', stamp " + std::to_string(msg->header.stamp.toSec()) + ")";
  try {
    auto cloud = std::make_shared<SurfelCloud>();
    PointCloud2Converter::fromMessage(*msg, *cloud);
    checkRenderableCloud(*cloud, /*require_patch_id=*/patch < 0);
    if (msg->header.frame_id.empty()) throw std::invalid_argument("header.frame_id is empty");
    if (msg->header.frame_id != params_.fixed_frame) {
      geometry_msgs::TransformStamped tf;
      try {
        // (the message filter has seen it transformable)
        tf = tf_buffer_.lookupTransform(params_.fixed_frame, msg->header.frame_id, msg->header.stamp);
      } catch (const tf2::TransformException& e) {
        throw std::runtime_error("no transform from '" + msg->header.frame_id + "' to '" +
                                 params_.fixed_frame + "': " + e.what());
      }
      cloud->transform(tf2::transformToEigen(tf));
      cloud->frame_id = params_.fixed_frame;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (sources_[source].cloud && !msg->header.stamp.isZero() && msg->header.stamp < sources_[source].stamp)
      throw std::invalid_argument("stamp " + std::to_string(msg->header.stamp.toSec()) +
                                  " older than the cloud shown (" +
                                  std::to_string(sources_[source].stamp.toSec()) + "): out of order");
    sources_[source].cloud = std::move(cloud);
    sources_[source].stamp = msg->header.stamp;
    inputs_changed_ = true;
    diagnostics_.accepted(patch < 0 ? std::string("surfels") : params_.patch_topics[size_t(patch)]);
  } catch (const std::exception& e) {
    diagnostics_.rejected(patch < 0 ? std::string("surfels") : params_.patch_topics[size_t(patch)], e.what());
    reject(what, e.what());
  }
}

bool CsgRenderer::setCsgTree(relaxed_connectivity::SetCsgTree::Request& request,
                             relaxed_connectivity::SetCsgTree::Response& response) {
  try {
    CsgTree tree = CsgTree::parse(request.expression);
    if (params_.splat.backface_culling && tree.hasComplementedPatches())
      throw std::invalid_argument(
          "backface_culling is on: a difference or complement would render wrongly (render two-sided)");
    response.success = true;
    response.message = tree.toString();
    std::lock_guard<std::mutex> lock(mutex_);
    tree_ = std::move(tree);
    expression_ = request.expression;
    inputs_changed_ = true;
    ROS_INFO_STREAM("csg_renderer: CSG tree set to " << response.message);
  } catch (const std::exception& e) {
    response.success = false;
    response.message = e.what();
    reject("CSG expression \"" + request.expression + "\"", e.what());
  }
  return true;
}

void CsgRenderer::reconfigure(relaxed_connectivity::SplatConfig& config, uint32_t) {
  std::string refused;  // reported after the lock (reject() takes it)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    SplatConfig splat = pending_splat_ ? *pending_splat_ : params_.splat;
    if (config.backface_culling && tree_ && tree_->hasComplementedPatches()) {
      refused = "backface_culling with a difference or complement in the tree renders wrongly";
      config.backface_culling = splat.backface_culling;
    }
    applySplatReconfigure(config, &splat);
    try {
      SurfelRenderer check(splat);  // validates
      pending_splat_ = splat;
      inputs_changed_ = true;            // re-render with them
    } catch (const std::exception& e) {  // answer with the settings that stay
      refused = e.what();
      writeSplatReconfigure(pending_splat_ ? *pending_splat_ : params_.splat, &config);
    }
  }
  if (!refused.empty()) reject("reconfigure", refused);
}

void CsgRenderer::renderBackground(const Camera& camera) {
  const size_t pixels = size_t(camera.width) * camera.height;
  images_.width = camera.width;
  images_.height = camera.height;
  images_.color.assign(pixels, params_.splat.background);
  images_.depth.assign(pixels, std::numeric_limits<float>::infinity());
  images_.normal.assign(pixels, Eigen::Vector3f::Zero());
  images_.weight.assign(pixels, 0.0f);
  images_.patch_id.assign(pixels, -1);
}

void CsgRenderer::timerCallback(const ros::WallTimerEvent&) {
  try {
    renderIfChanged();
  } catch (const std::exception& e) {  // never let a frame take the node down
    reject("frame", e.what());
  }
}

bool CsgRenderer::renderIfChanged() {
  // The camera pose: the latest transform available.
  geometry_msgs::TransformStamped camera_tf;
  try {
    camera_tf = tf_buffer_.lookupTransform(params_.fixed_frame, params_.camera_frame, ros::Time(0));
  } catch (const tf2::TransformException& e) {
    ROS_WARN_STREAM_THROTTLE(5.0, "csg_renderer: no camera pose (transform '"
                                      << params_.fixed_frame << "' -> '" << params_.camera_frame
                                      << "'): " << e.what() << "; keeping the last frame");
    return false;
  }
  const Eigen::Isometry3d pose = tf2::transformToEigen(camera_tf);
  if (!pose.matrix().allFinite()) {
    reject("camera pose", "the transform to '" + params_.camera_frame + "' is not finite");
    return false;
  }
  const bool moved = !last_pose_ || cameraPoseMoved(*last_pose_, pose, params_.pose_tolerance);

  // Snapshot of the inputs.
  std::vector<Source> sources;
  std::optional<CsgTree> tree;
  std::string expression;
  bool inputs_changed;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    inputs_changed = inputs_changed_;
    if (!inputs_changed && !moved) return false;
    inputs_changed_ = false;
    sources = sources_;
    tree = tree_;
    expression = expression_;
    if (pending_splat_) {
      params_.splat = *pending_splat_;
      renderer_ = SurfelRenderer(params_.splat);
      pending_splat_.reset();
    }
  }

  const Clock::time_point start_prepare = Clock::now();
  if (inputs_changed) {
    // Build the new patch set aside; the last good one stays if this throws.
    std::vector<PatchCloudInput> inputs;
    for (size_t i = 0; i < sources.size(); ++i)
      if (sources[i].cloud) inputs.push_back({sources[i].cloud.get(), i == 0 ? -1 : int(i) - 1});
    CsgClipperOptions options;
    options.method = parsePartnerMethod(params_.partner_method);
    patches_ = std::make_unique<PatchCloudSet>(inputs, tree, params_.fixed_frame, options);
  }
  if (!patches_) return false;  // no input yet

  Camera camera = params_.camera();
  camera.world_T_camera = pose;
  // Clip buffer partners depend on the view (Algorithm 4.1); the spatial index's were found at construction.
  CsgClipper* clipper = patches_->clipper();
  if (clipper && (clipper->options().method == PartnerMethod::kClipBuffer)) clipper->update(camera);
  const double prepare_time = secondsSince(start_prepare);

  const Clock::time_point start_render = Clock::now();
  RenderStats render_stats;
  if (patches_->cloud().empty())
    renderBackground(camera);  // e.g. a tree naming only patches that have not arrived
  else
    renderer_.render(patches_->cloud(), camera, &images_, clipper, &render_stats);
  const double render_time = secondsSince(start_render);
  last_pose_ = pose;

  std_msgs::Header header;
  header.frame_id = params_.camera_frame;
  header.stamp = camera_tf.header.stamp;
  for (const Source& s : sources)
    if (s.cloud && s.stamp > header.stamp) header.stamp = s.stamp;
  if (header.stamp.isZero()) header.stamp = ros::Time::now();
  image_pub_.publish(toColorImage(images_, header));
  depth_pub_.publish(toDepthImage(images_, header));
  patch_pub_.publish(toPatchIdImage(images_, header));
  info_pub_.publish(toCameraInfo(camera, header));
  ++rendered_frames_;

  relaxed_connectivity::CsgRenderStats stats;
  stats.header = header;
  stats.csg = expression;
  stats.patches = uint32_t(patchIds(patches_->cloud()).size());
  stats.surfels = uint32_t(render_stats.surfels);
  stats.splats = uint32_t(render_stats.splats);
  stats.fragments = uint32_t(render_stats.fragments);
  stats.clipped_fragments = uint32_t(render_stats.clipped_fragments);
  stats.foreground_pixels = uint32_t(countForegroundPixels(images_));
  stats.prepare_time = prepare_time;
  stats.render_time = render_time;
  stats.rendered_frames = rendered_frames_;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stats.rejected_inputs = rejected_inputs_;
    stats.last_error = last_error_;
  }
  stats_pub_.publish(stats);
  ROS_DEBUG_STREAM("csg_renderer: frame " << rendered_frames_ << ": " << stats.surfels << " surfels, "
                                          << stats.fragments << " fragments (" << stats.clipped_fragments
                                          << " clipped), prepare " << 1e3 * prepare_time << " ms, render "
                                          << 1e3 * render_time << " ms");
  return true;
}

}  // namespace rc
