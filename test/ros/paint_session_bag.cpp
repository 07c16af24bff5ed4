// The recorded paint session bag through the session's nodes (paint_session_bag.test): the object is scanned
// and painted, the renderer follows every delta differentially, and its last image equals a full render of
// the state paint_model saves (same parameters, same camera) within the differential rendering bound of
// test_painted_cloud_mirror (acrylic's imprints: mean below 6 levels over the painted pixels; here over the
// image, where most pixels are unpainted and exact). The same inputs run offline through the core (the
// object paint_model received, the device poses its main loop stepped to, read from brush_contact's stamps)
// give the same painted state: surfel counts, wet volume, colours at probes.
#include <relaxed_connectivity/BrushContact.h>
#include <relaxed_connectivity/PaintFile.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <cstdio>
#include <map>

#include "paint_session_support.h"
#include "relaxed_connectivity/paint/brush_preset_reader.h"
#include "relaxed_connectivity/paint/paint_transfer.h"
#include "relaxed_connectivity/paint/paint_type_reader.h"
#include "relaxed_connectivity/paint/painted_surface_io.h"
#include "relaxed_connectivity/render/splat/differential_renderer.h"
#include "relaxed_connectivity/ros/paint_model.h"
#include "relaxed_connectivity/ros/paint_renderer.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

/// What paint_model received and did, for an offline replay: the objects on its input, every device pose,
/// and the pose stamp of each main-loop tick (brush_contact carries it, one per tick with a pose).
struct PaintModelInputs {
  explicit PaintModelInputs(ros::NodeHandle& nh) {
    objects = nh.subscribe<sensor_msgs::PointCloud2>("surfels_accumulated", 10,
                                                     [this](const auto& m) { object = m; });
    poses = nh.subscribe<geometry_msgs::PoseStamped>(
        "haptic/pose", 100000, [this](const auto& m) { pose_at[m->header.stamp.toNSec()] = m; });
    contacts =
        nh.subscribe<relaxed_connectivity::BrushContact>("brush_contact", 100000, [this](const auto& m) {
          tick_stamps.push_back(m->header.stamp.toNSec());
          pose_frame = m->header.frame_id;
        });
  }
  ros::Subscriber objects, poses, contacts;
  sensor_msgs::PointCloud2ConstPtr object;
  std::map<uint64_t, geometry_msgs::PoseStampedConstPtr> pose_at;
  std::vector<uint64_t> tick_stamps;
  std::string pose_frame;
};

struct Session {
  Session() : observer(nh), inputs(nh), tf_listener(tf_buffer) {}
  /// Waits once for the bag's end and the renderer's stats after it.
  bool ended() {
    if (!ended_) {
      ended_ =
          observer.waitForTheEnd(90.0) &&
          waitFor([&] { return observer.render_stats.header.stamp > ros::Time::now() - ros::Duration(0.5); },
                  5);
      if (ended_) saved = savedState();
    }
    return ended_ && saved;
  }
  Eigen::Isometry3d transform(const std::string& target, const std::string& source) {
    waitFor([&] { return tf_buffer.canTransform(target, source, ros::Time(0)); }, 5);
    return tf2::transformToEigen(tf_buffer.lookupTransform(target, source, ros::Time(0)));
  }
  /// The state paint_model saves (~save), loaded back.
  static std::unique_ptr<PaintSurface> savedState() {
    relaxed_connectivity::PaintFile save;
    save.request.path = "/tmp/paint_session_bag_" + std::to_string(::getpid()) + ".ply";
    if (!ros::service::call("paint_model/save", save) || !save.response.success) {
      ADD_FAILURE() << "paint_model/save: " << save.response.message;
      return nullptr;
    }
    std::unique_ptr<PaintSurface> state = loadPaintedSurface(save.request.path);
    std::remove(save.request.path.c_str());
    return state;
  }

  ros::NodeHandle nh;
  SessionObserver observer;
  PaintModelInputs inputs;
  tf2_ros::Buffer tf_buffer;
  tf2_ros::TransformListener tf_listener;
  std::unique_ptr<PaintSurface> saved;
  bool ended_ = false;
};
Session* session_ = nullptr;  // one session per test process (the bag plays once)

TEST(PaintSessionBag, PaintsAndTheImageEqualsAFullRenderOfTheSavedState) {
  ASSERT_TRUE(session_->ended()) << session_->observer.pose_count << " poses, "
                                 << session_->observer.delta_count << " deltas";
  const SessionObserver& session = session_->observer;

  // Painted: children made by resampling, wet paint; nothing refused.
  const relaxed_connectivity::PaintStats& p = session.paint_stats;
  EXPECT_GT(p.originals, 10000u);
  EXPECT_GT(p.children, 500u);
  EXPECT_GT(p.wet_surfels, 500u);
  EXPECT_EQ(p.rejected_messages, 0u);
  EXPECT_EQ(p.instabilities, 0u);
  // Rendered: mostly differential updates, no gap, nothing refused, the copy as large as the object.
  const relaxed_connectivity::PaintRenderStats& r = session.render_stats;
  EXPECT_GT(session.differential_updates, 20u);
  EXPECT_GT(session.differential_updates, 4 * session.full_updates);
  EXPECT_EQ(r.sequence_gaps, 0u);
  EXPECT_EQ(r.rejected_messages, 0u) << r.last_error;
  EXPECT_EQ(r.surfels, p.active_surfels);

  // The saved state, rendered whole with the node's parameters and camera.
  const std::unique_ptr<PaintSurface>& saved = session_->saved;
  EXPECT_EQ(saved->activeCount(), r.surfels);
  const PaintRendererParams params = readPaintRendererParams(ros::NodeHandle("paint_renderer"));
  Camera camera = params.camera();
  camera.world_T_camera = session_->transform(params.fixed_frame, params.camera_frame);
  DifferentialRenderConfig config = params.render;
  const EnvironmentMap studio = EnvironmentMap::studio();  // the node's default environment
  ASSERT_EQ(params.environment, "studio");
  config.splat.environment = &studio;
  DifferentialSurfelRenderer reference(config);
  reference.renderFull(saved->activeCloud(), camera);

  ASSERT_TRUE(session.image);
  const sensor_msgs::Image& image = *session.image;
  ASSERT_EQ(image.width, camera.width);
  ASSERT_EQ(image.height, camera.height);
  double mean = 0;
  size_t over_eight = 0, painted = 0;
  const std::vector<Rgba>& expected = reference.images().color;
  for (size_t i = 0; i < expected.size(); ++i) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(image.data[3 * i + c]) - int(expected[i][c])));
    mean += d;
    over_eight += d > 8;
  }
  mean /= double(expected.size());
  for (const auto& c : saved->activeCloud().colors)
    painted += c[0] > 2 * c[2];  // red acrylic on the purple box
  std::printf(
      "session: %u originals, %u children, %zu deltas; image against a full render: mean %.3f levels, "
      "%zu of %zu pixels over 8 levels; %zu red surfels\n",
      p.originals, p.children, session.delta_count, mean, over_eight, expected.size(), painted);
  EXPECT_LT(mean, 0.5);
  EXPECT_LT(double(over_eight), 0.01 * double(expected.size()));
  EXPECT_GT(painted, 200u);
}

TEST(PaintSessionBag, TheSameInputsOfflineThroughTheCoreGiveTheSamePaintedState) {
  ASSERT_TRUE(session_->ended());
  const PaintModelInputs& in = session_->inputs;
  ASSERT_TRUE(in.object) << "no object on surfels_accumulated";
  ASSERT_GT(in.tick_stamps.size(), 100u);
  const PaintModelParams params = readPaintModelParams(ros::NodeHandle("paint_model"));
  ASSERT_FALSE(params.paint.empty());

  // The object as paint_model installs it (the last one before the paint: the bag's scan ends first).
  SurfelCloud cloud = PointCloud2Converter::fromMessage(*in.object);
  cloud.removeNonFinite();
  if (in.object->header.frame_id != params.world_frame)
    cloud.transform(session_->transform(params.world_frame, in.object->header.frame_id));
  PaintSurface offline(std::move(cloud));
  ASSERT_EQ(offline.originalCount(), session_->observer.paint_stats.originals);

  // The main loop's ticks (5.2, Fig. 5.4): the brush steps to each tick's pose, then transfers paint.
  Brush brush(readBrushPreset(params.brush), params.brush_options);
  const PaintType paint = readPaintType(params.paint);
  loadBrush(brush.skin(), paint);
  const Eigen::Isometry3d world_T_pose_frame = session_->transform(params.world_frame, in.pose_frame);
  const double dt = 1.0 / params.rate;
  size_t painting_ticks = 0;
  for (size_t k = 0; k < in.tick_stamps.size(); ++k) {
    const auto pose = in.pose_at.find(in.tick_stamps[k]);
    ASSERT_NE(pose, in.pose_at.end()) << "tick " << k << ": a pose the test did not receive";
    Eigen::Isometry3d pose_frame_T_stylus;
    tf2::fromMsg(pose->second->pose, pose_frame_T_stylus);
    const Eigen::Isometry3d world_T_stylus = world_T_pose_frame * pose_frame_T_stylus;
    if (k == 0) brush.reset(world_T_stylus);
    brush.advance(dt, world_T_stylus, &offline);
    painting_ticks += transferPaint(brush, offline, paint, dt, params.transfer).penetrated_pixels > 0;
  }

  // The same state: counts, wet paint, the colour and position of every surfel.
  const PaintSurface& live = *session_->saved;
  ASSERT_EQ(live.originalCount(), offline.originalCount());
  EXPECT_EQ(live.childCount(), offline.childCount());
  EXPECT_EQ(live.activeCount(), offline.activeCount());
  const double wet_live = surfaceWetVolume(live), wet_offline = surfaceWetVolume(offline);
  EXPECT_NEAR(wet_live, wet_offline, 1e-4 * wet_offline);
  // Every active surfel, in the order both surfaces list them (originals, then each one's children).
  const SurfelCloud a = live.activeCloud(), b = offline.activeCloud();
  ASSERT_EQ(a.size(), b.size());
  int worst = 0;
  size_t differing = 0, painted = 0;
  double farthest = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    int d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(int(a.colors[i][c]) - int(b.colors[i][c])));
    worst = std::max(worst, d);
    differing += d > 1;
    painted += b.colors[i][0] > 2 * b.colors[i][2];  // red acrylic on the purple box
    farthest = std::max(farthest, (a.positions[i] - b.positions[i]).norm());
  }
  std::printf(
      "offline replay of %zu ticks (%zu painting): %zu / %zu children (live / offline), wet volume %.6g / "
      "%.6g, %zu active surfels (%zu red) compared: %zu differ by more than one level (worst %d), positions "
      "within %.2g m\n",
      in.tick_stamps.size(), painting_ticks, live.childCount(), offline.childCount(), wet_live, wet_offline,
      a.size(), painted, differing, worst, farthest);
  EXPECT_GT(painted, 200u);
  EXPECT_EQ(differing, 0u);
  EXPECT_LT(farthest, 1e-6);  // (the saved state's float positions)
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_session_bag");
  rc::Session session;  // subscribes before the bag plays (the launch delays it)
  rc::session_ = &session;
  return RUN_ALL_TESTS();
}
