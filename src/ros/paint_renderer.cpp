#include "relaxed_connectivity/ros/paint_renderer.h"

#include <relaxed_connectivity/PaintRenderStats.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_eigen/tf2_eigen.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "relaxed_connectivity/paint/painted_surface_io.h"
#include "relaxed_connectivity/render/splat/image_io.h"
#include "relaxed_connectivity/ros/csg_renderer_images.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"
#include "relaxed_connectivity/ros/splat_params.h"

namespace rc {
namespace {

constexpr size_t kRecentDeltas = 30;  ///< half a second of deltas at 60 Hz, for a full cloud that comes late

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, size_t(q * double(values.size())))];
}

/// Sum of the positions and colours of a cloud (any order gives the same value up to rounding).
double positionChecksum(const SurfelCloud& cloud) {
  double sum = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Vec3& p = cloud.positions[i];
    sum += p.x() + 1.618 * p.y() + 2.718 * p.z();
    if (cloud.hasColors())
      sum += 1e-3 * (cloud.colors[i][0] + 3 * cloud.colors[i][1] + 7 * cloud.colors[i][2]);
  }
  return sum;
}

}  // namespace

void PaintRendererParams::validate() const {
  auto fail = [](const std::string& what) { throw std::invalid_argument("paint_renderer: " + what); };
  if (fixed_frame.empty() || camera_frame.empty()) fail("fixed_frame and camera_frame must not be empty");
  if (!(max_rate > 0) || !std::isfinite(max_rate)) fail("max_rate must be > 0 Hz");
  if (!(stats_period > 0) || !std::isfinite(stats_period)) fail("stats_period must be > 0 s");
  if (width < 1 || height < 1 || width > 16384 || height > 16384)
    fail("width and height must lie in [1, 16384] (got " + std::to_string(width) + " x " +
         std::to_string(height) + ")");
  if (!(horizontal_fov > 0 && horizontal_fov < 180)) fail("horizontal_fov must lie in (0, 180) degrees");
  if (!(near_clip > 0) || !(far_clip > near_clip) || !std::isfinite(far_clip))
    fail("need 0 < near_clip < far_clip");
  try {
    render.validate();
    SurfelRenderer check(render.splat);
    brush.validate();
  } catch (const std::invalid_argument& e) {
    fail(e.what());
  }
}

Camera PaintRendererParams::camera() const {
  Camera camera = Camera::perspective(uint32_t(width), uint32_t(height), horizontal_fov * M_PI / 180.0);
  camera.near_clip = near_clip;
  camera.far_clip = far_clip;
  return camera;
}

PaintRendererParams readPaintRendererParams(const ros::NodeHandle& pnh) {
  PaintRendererParams p;
  pnh.param("fixed_frame", p.fixed_frame, p.fixed_frame);
  pnh.param("camera_frame", p.camera_frame, p.camera_frame);
  pnh.param("max_rate", p.max_rate, p.max_rate);
  pnh.param("stats_period", p.stats_period, p.stats_period);
  pnh.param("width", p.width, p.width);
  pnh.param("height", p.height, p.height);
  pnh.param("horizontal_fov", p.horizontal_fov, p.horizontal_fov);
  pnh.param("near_clip", p.near_clip, p.near_clip);
  pnh.param("far_clip", p.far_clip, p.far_clip);
  SplatConfig& s = p.render.splat;
  s.outputs = kOutputColor | kOutputDepth | kOutputWeight;  // what the node publishes
  readSplatParams(pnh, "paint_renderer", &s);
  int max_delta = int(std::min<size_t>(p.render.max_delta_surfels, 1u << 30));
  int max_tile_updates = int(p.render.max_tile_updates);
  pnh.param("max_delta_surfels", max_delta, max_delta);
  pnh.param("max_tile_updates", max_tile_updates, max_tile_updates);
  if (max_delta < 0 || max_tile_updates < 1)
    throw std::invalid_argument("paint_renderer: max_delta_surfels must be >= 0 and max_tile_updates >= 1");
  p.render.max_delta_surfels = size_t(max_delta);
  p.render.max_tile_updates = uint32_t(max_tile_updates);
  p.render.pose_tolerance =
      1e-6;  // camera motion [m, rad] that makes a full update (node and renderer alike)
  pnh.param("pose_tolerance", p.render.pose_tolerance, p.render.pose_tolerance);
  pnh.param("environment", p.environment, p.environment);
  pnh.param("draw_brush", p.draw_brush, p.draw_brush);
  OverlayOptions& b = p.brush;
  b.splat = s;
  pnh.param("shadow", b.shadow, b.shadow);
  std::vector<double> light{b.light_direction.x(), b.light_direction.y(), b.light_direction.z()};
  pnh.param("light_direction", light, light);
  if (light.size() != 3) throw std::invalid_argument("paint_renderer: light_direction must be [x, y, z]");
  b.light_direction = Vec3(light[0], light[1], light[2]);
  pnh.param("shadow_length", b.shadow_length, b.shadow_length);
  pnh.param("shadow_strength", b.shadow_strength, b.shadow_strength);
  p.validate();
  return p;
}

namespace {

std::unique_ptr<EnvironmentMap> makeEnvironment(const std::string& spec) {
  if (spec == "none") return nullptr;
  if (spec == "studio") return std::make_unique<EnvironmentMap>(EnvironmentMap::studio());
  try {
    return std::make_unique<EnvironmentMap>(EnvironmentMap::fromEquirectangularPng(spec));
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("paint_renderer: environment: ") + e.what());
  }
}

DifferentialRenderConfig withEnvironment(DifferentialRenderConfig config, const EnvironmentMap* environment) {
  config.splat.environment = environment;
  return config;
}

}  // namespace

PaintRenderer::PaintRenderer(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(nh),
      private_nh_(private_nh),
      params_(readPaintRendererParams(private_nh)),
      tf_listener_(tf_buffer_, nh),
      environment_(makeEnvironment(params_.environment)),
      renderer_(withEnvironment(params_.render, environment_.get())),
      compositor_(params_.brush),
      diagnostics_(nh, private_nh, "paint_renderer") {
  image_pub_ = private_nh_.advertise<sensor_msgs::Image>("image", 1);
  depth_pub_ = private_nh_.advertise<sensor_msgs::Image>("depth", 1);
  info_pub_ = private_nh_.advertise<sensor_msgs::CameraInfo>("camera_info", 1, /*latch=*/true);
  stats_pub_ = private_nh_.advertise<relaxed_connectivity::PaintRenderStats>("stats", 10);
  save_srv_ = private_nh_.advertiseService("save_image", &PaintRenderer::saveImage, this);
  painted_sub_ = nh_.subscribe("surfels/painted", 2, &PaintRenderer::paintedCallback, this);
  delta_sub_ = nh_.subscribe("surfels/painted_delta", 100, &PaintRenderer::deltaCallback, this,
                             ros::TransportHints().tcpNoDelay());
  if (params_.draw_brush) skin_sub_ = nh_.subscribe("brush/skin", 2, &PaintRenderer::skinCallback, this);
  diagnostics_.addInput(painted_sub_.getTopic(), 0.0);  // latched, comes now and then
  diagnostics_.addInput(delta_sub_.getTopic(), 0.0);    // only while painting
  last_stats_ = last_frame_ = ros::WallTime::now();
  reconfigure_server_ =
      std::make_unique<dynamic_reconfigure::Server<relaxed_connectivity::SplatConfig>>(private_nh_);
  reconfigure_server_->setCallback(
      [this](relaxed_connectivity::SplatConfig& config, uint32_t level) { reconfigure(config, level); });
  timer_ =
      nh_.createWallTimer(ros::WallDuration(0.25 / params_.max_rate), &PaintRenderer::timerCallback, this);
  ROS_INFO_STREAM("paint_renderer: camera '" << params_.camera_frame << "' in '" << params_.fixed_frame
                                             << "', " << params_.width << " x " << params_.height
                                             << ", at most " << params_.max_rate << " Hz, brush "
                                             << (params_.draw_brush ? "drawn" : "not drawn"));
}

PaintRenderer::~PaintRenderer() {
  timer_.stop();
}

void PaintRenderer::reject(const std::string& what, const std::string& reason) {
  const std::string text = "rejected " + what + ": " + reason;
  ROS_ERROR_STREAM_THROTTLE(1.0, "paint_renderer: " << text);
  std::lock_guard<std::mutex> lock(mutex_);
  ++rejected_;
  last_error_ = text;
}

SurfelCloud PaintRenderer::cloudOf(const sensor_msgs::PointCloud2& msg, const char* what,
                                   bool need_father) const {
  if (msg.header.frame_id != params_.fixed_frame)
    throw std::invalid_argument(std::string(what) + " in frame '" + msg.header.frame_id + "', expected '" +
                                params_.fixed_frame + "' (fixed_frame: the paint model's world_frame)");
  SurfelCloud cloud;
  PointCloud2Converter::fromMessage(msg, cloud);
  if (!cloud.empty() && !(cloud.hasNormals() && cloud.hasRadii()))
    throw std::invalid_argument(std::string(what) + " has no normals or radii");
  if (need_father && !cloud.empty()) {  // (checked here, so a cloud the mirror cannot take is not "accepted")
    const Attribute* father = cloud.attributes.find(kSurfelFather);
    if (!father || father->type != ScalarType::kUInt32 || father->count != 1)
      throw std::invalid_argument(std::string(what) + " has no uint32 column '" + kSurfelFather +
                                  "' (the paint model's surfel ids)");
  }
  cloud.removeNonFinite();  // (what cannot be drawn never enters the copy)
  return cloud;
}

void PaintRenderer::paintedCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  try {
    const ros::Time stamp = msg->header.stamp;
    {
      // A full cloud comes once in a while and travels slower than the deltas: the copy may be newer already
      // (then the cloud is not even converted).
      std::lock_guard<std::mutex> lock(mutex_);
      if (!waiting_ && have_object_ && !gap_ && last_delta_stamp_ > stamp) return;
    }
    const SurfelCloud cloud = cloudOf(*msg, "full cloud", true);
    if (cloud.empty())  // (the paint model never sends an empty object: this one would blank the view)
      throw std::invalid_argument(msg->width * msg->height ? "full cloud has no finite surfel"
                                                           : "full cloud has no points");
    diagnostics_.accepted(painted_sub_.getTopic());  // well-formed
    std::lock_guard<std::mutex> lock(mutex_);
    if (waiting_) {  // deltas of a new object wait for its first full cloud; an older cloud is the old object
      if (stamp < waiting_stamp_) return;
      waiting_ = false;
      generation_known_ = true;
      return resync(cloud, stamp);
    }
    if (have_object_ && !gap_) {
      if (last_delta_stamp_ > stamp) return;
      // The deltas brought the copy to this state: same surfels (count and an order-free checksum).
      const double checksum = positionChecksum(cloud);
      if (mirror_.size() == cloud.size() &&
          std::abs(positionChecksum(mirror_.cloud()) - checksum) <= 1e-9 * (1.0 + std::abs(checksum)))
        return;
    }
    resync(cloud, stamp);
  } catch (const std::exception& e) {
    diagnostics_.rejected(painted_sub_.getTopic(), e.what());
    reject("full cloud (stamp " + std::to_string(msg->header.stamp.toSec()) + ")", e.what());
  }
}

void PaintRenderer::resync(const SurfelCloud& cloud, const ros::Time& stamp) {
  mirror_.reset(cloud);                         // (throws before changing anything)
  for (const AppliedDelta& d : recent_deltas_)  // deltas after this cloud that came before it
    if (d.stamp > stamp && (!generation_known_ || d.generation == copy_generation_))
      mirror_.applyDelta(d.originals, d.surfels, nullptr, nullptr);
  have_object_ = true;
  copy_stamp_ = stamp;
  gap_ = false;
  resynced_ = dirty_ = true;
  ++resyncs_;
  pending_removed_ = SurfelCloud();
  pending_added_ = SurfelCloud();
}

void PaintRenderer::applyDelta(const std::vector<uint32_t>& originals, const SurfelCloud& surfels,
                               const ros::Time& pose_stamp) {
  const size_t removed = pending_removed_.size(), added = pending_added_.size();
  mirror_.applyDelta(originals, surfels, &pending_removed_, &pending_added_);
  delta_surfels_ += uint32_t(pending_removed_.size() - removed + pending_added_.size() - added);
  pending_pose_stamps_.push_back(pose_stamp);
  ++deltas_;
  dirty_ = true;
}

void PaintRenderer::deltaCallback(const relaxed_connectivity::PaintDeltaConstPtr& msg) {
  try {
    SurfelCloud surfels = cloudOf(msg->surfels, "delta", true);
    diagnostics_.accepted(delta_sub_.getTopic());
    std::lock_guard<std::mutex> lock(mutex_);
    if (last_sequence_ != 0 && msg->sequence != last_sequence_ + 1) {
      gap_ = true;
      ++sequence_gaps_;
      ROS_WARN_STREAM_THROTTLE(1.0, "paint_renderer: delta "
                                        << msg->sequence << " after " << last_sequence_
                                        << ": missed deltas; waiting for the next full cloud");
    }
    last_sequence_ = msg->sequence;
    if (!generation_known_ || msg->object_generation != copy_generation_) {
      // A new object: the copy is of it if it was made from a full cloud of this generation.
      copy_generation_ = msg->object_generation;
      generation_known_ = true;
      waiting_ = !(have_object_ && copy_stamp_ >= msg->object_stamp);
      waiting_stamp_ = msg->object_stamp;
    }
    if (have_object_ && !waiting_) applyDelta(msg->originals, surfels, msg->pose_stamp);
    last_delta_stamp_ = msg->header.stamp;
    // Kept with what the copy needs only (the paint columns are most of a delta's bytes).
    for (auto it = surfels.attributes.columns().begin(); it != surfels.attributes.columns().end();)
      it = it->name == kSurfelFather ? std::next(it) : surfels.attributes.columns().erase(it);
    surfels.confidence.clear();
    surfels.curvature.clear();
    recent_deltas_.push_back({msg->header.stamp, msg->object_generation, msg->originals, std::move(surfels)});
    if (recent_deltas_.size() > kRecentDeltas) recent_deltas_.pop_front();
  } catch (const std::exception& e) {
    diagnostics_.rejected(delta_sub_.getTopic(), e.what());
    reject("delta " + std::to_string(msg->sequence), e.what());
  }
  renderWhenDue();  // the paint on screen as soon as a frame is due (end-to-end latency)
}

void PaintRenderer::skinCallback(const sensor_msgs::PointCloud2ConstPtr& msg) {
  try {
    SurfelCloud skin = cloudOf(*msg, "brush skin", false);
    std::lock_guard<std::mutex> lock(mutex_);
    skin_ = std::move(skin);
    dirty_ = true;
  } catch (const std::exception& e) {
    reject("brush skin", e.what());
  }
}

bool PaintRenderer::saveImage(relaxed_connectivity::PaintFile::Request& request,
                              relaxed_connectivity::PaintFile::Response& response) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    const RenderImages& images = renderer_.images();
    if (!renderer_.valid() || images.color.empty()) throw std::runtime_error("no image rendered yet");
    const std::vector<Rgba>& color = composed_.size() == images.color.size() ? composed_ : images.color;
    writePng(request.path, color, images.width, images.height);
    response.success = true;
    response.message = "wrote " + request.path;
  } catch (const std::exception& e) {
    response.success = false;
    response.message = e.what();
  }
  return true;
}

void PaintRenderer::reconfigure(relaxed_connectivity::SplatConfig& config, uint32_t) {
  std::lock_guard<std::mutex> lock(mutex_);
  SplatConfig splat = renderer_.config().splat;
  applySplatReconfigure(config, &splat);
  if (sameSplatReconfigure(splat, renderer_.config().splat))
    return;  // e.g. the server's first call: the settings as they are
  try {
    renderer_.setSplatConfig(splat);
    dirty_ = true;
  } catch (const std::exception& e) {  // answer with the settings that stay
    ROS_ERROR_STREAM("paint_renderer: refused splat settings: " << e.what());
    writeSplatReconfigure(renderer_.config().splat, &config);
  }
}

void PaintRenderer::timerCallback(const ros::WallTimerEvent&) {
  renderWhenDue();
  const ros::WallTime now = ros::WallTime::now();
  if ((now - last_stats_).toSec() >= params_.stats_period) publishStats(now);
}

void PaintRenderer::renderWhenDue() {
  std::unique_lock<std::mutex> frame(frame_mutex_, std::try_to_lock);
  if (!frame.owns_lock()) return;  // another thread renders now; the timer catches what it missed
  const ros::WallTime now = ros::WallTime::now();
  if ((now - last_frame_).toSec() < 1.0 / params_.max_rate - 1e-4) return;
  try {
    if (renderIfChanged()) last_frame_ = now;
  } catch (const std::exception& e) {  // never let a frame take the node down
    reject("frame", e.what());
  }
}

bool PaintRenderer::renderIfChanged() {
  geometry_msgs::TransformStamped camera_tf;
  try {
    camera_tf = tf_buffer_.lookupTransform(params_.fixed_frame, params_.camera_frame, ros::Time(0));
  } catch (const tf2::TransformException& e) {
    ROS_WARN_STREAM_THROTTLE(5.0, "paint_renderer: no camera pose (transform '"
                                      << params_.fixed_frame << "' -> '" << params_.camera_frame
                                      << "'): " << e.what() << "; keeping the last frame");
    return false;
  }
  Camera camera = params_.camera();
  camera.world_T_camera = tf2::transformToEigen(camera_tf);
  if (!camera.world_T_camera.matrix().allFinite()) {
    reject("camera pose", "the transform to '" + params_.camera_frame + "' is not finite");
    return false;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (!have_object_) return false;
  const bool moved = !last_camera_ || cameraPoseMoved(last_camera_->world_T_camera, camera.world_T_camera,
                                                      params_.render.pose_tolerance);
  if (!dirty_ && !moved) return false;
  if (!moved) camera = *last_camera_;  // within the tolerance: the sums stay valid
  if (resynced_) renderer_.invalidate();
  DifferentialStats st;
  renderer_.update(mirror_.cloud(), pending_removed_, pending_added_, camera, &st);
  if (st.update == RenderUpdate::kFull) {
    last_reason_ = resynced_ && last_camera_ ? "resync" : fullUpdateReasonName(st.reason);
    ++full_updates_;
    full_ms_ += st.total_ms;
  } else {
    ++differential_updates_;
    differential_ms_ += st.total_ms;
    differential_max_ms_ = std::max(differential_max_ms_, st.total_ms);
  }
  pending_removed_ = SurfelCloud();
  pending_added_ = SurfelCloud();
  resynced_ = dirty_ = false;
  const RenderImages& images = renderer_.images();
  const std::vector<Rgba>* color = &images.color;
  if (params_.draw_brush && !skin_.empty()) {
    OverlayStats os;
    compositor_.composite(skin_, camera, images, &composed_, &os);
    brush_ms_ += os.ms;
    color = &composed_;
  } else {
    composed_.clear();
  }

  std_msgs::Header header;
  header.frame_id = params_.camera_frame;
  header.stamp = std::max(camera_tf.header.stamp, last_delta_stamp_);
  if (header.stamp.isZero()) header.stamp = ros::Time::now();
  if (image_pub_.getNumSubscribers() > 0)
    image_pub_.publish(toColorImage(*color, images.width, images.height, header));
  if (depth_pub_.getNumSubscribers() > 0) depth_pub_.publish(toDepthImage(images, header));
  if (moved || frames_ == 0) info_pub_.publish(toCameraInfo(camera, header));
  last_camera_ = camera;
  const ros::Time shown = ros::Time::now();
  for (const ros::Time& pose_stamp : pending_pose_stamps_)
    if (!pose_stamp.isZero()) {
      latencies_ms_.push_back(1e3 * (shown - pose_stamp).toSec());
      session_latency_.add(latencies_ms_.back());
    }
  pending_pose_stamps_.clear();
  ++frames_;
  return true;
}

void PaintRenderer::publishStats(const ros::WallTime& now) {
  relaxed_connectivity::PaintRenderStats s;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    s.header.stamp = ros::Time::now();
    s.surfels = uint32_t(mirror_.size());
    s.frames = frames_;
    s.full_updates = full_updates_;
    s.differential_updates = differential_updates_;
    s.last_full_update_reason = last_reason_;
    s.deltas = deltas_;
    s.delta_surfels = delta_surfels_;
    s.full_update_ms = full_updates_ ? full_ms_ / full_updates_ : 0.0;
    s.differential_update_ms = differential_updates_ ? differential_ms_ / differential_updates_ : 0.0;
    s.differential_update_max_ms = differential_max_ms_;
    s.brush_ms = frames_ ? brush_ms_ / frames_ : 0.0;
    s.latency_p50_ms = percentile(latencies_ms_, 0.5);
    s.latency_p99_ms = percentile(latencies_ms_, 0.99);
    s.latency_max_ms =
        latencies_ms_.empty() ? 0.0 : *std::max_element(latencies_ms_.begin(), latencies_ms_.end());
    s.session_latency_count = uint32_t(session_latency_.count());
    s.session_latency_p50_ms = session_latency_.percentile(0.5);
    s.session_latency_p99_ms = session_latency_.percentile(0.99);
    s.session_latency_max_ms = session_latency_.max();
    s.sequence_gaps = sequence_gaps_;
    s.resyncs = resyncs_;
    s.rejected_messages = rejected_;
    s.last_error = last_error_;
    frames_ = full_updates_ = differential_updates_ = deltas_ = delta_surfels_ = 0;
    full_ms_ = differential_ms_ = differential_max_ms_ = brush_ms_ = 0;
    latencies_ms_.clear();
  }
  stats_pub_.publish(s);
  last_stats_ = now;
}

}  // namespace rc
