// paint_model's services and messages in a running session (launch/brush_demo.launch): deltas, undo/redo,
// save/load, clear, set_paint, a second object while painted, stats, dynamic_reconfigure of brush and paint.
// (boost::function inside actionlib's client warns of a maybe-uninitialized copy with GCC 12)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <actionlib/client/simple_action_client.h>
#pragma GCC diagnostic pop
#include <gtest/gtest.h>
#include <relaxed_connectivity/BrushContact.h>
#include <relaxed_connectivity/LoadPaintedStateAction.h>
#include <relaxed_connectivity/PaintCommand.h>
#include <relaxed_connectivity/PaintDelta.h>
#include <relaxed_connectivity/PaintFile.h>
#include <relaxed_connectivity/PaintStats.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <mutex>
#include <vector>

#include "reconfigure_support.h"
#include "relaxed_connectivity/paint/paint_palette.h"
#include "relaxed_connectivity/ros/point_cloud2_converter.h"

namespace rc {
namespace {

/// The surfels of a cloud per father (position and colour), the form deltas are applied in.
using Surfels = std::map<uint32_t, std::vector<std::array<double, 6>>>;

Surfels byFather(const sensor_msgs::PointCloud2& msg) {
  const SurfelCloud c = PointCloud2Converter::fromMessage(msg);
  const Attribute* father = c.attributes.find("father");
  EXPECT_NE(father, nullptr);
  Surfels out;
  for (size_t i = 0; father && i < c.size(); ++i)
    out[uint32_t(father->get(i))].push_back({c.positions[i].x(), c.positions[i].y(), c.positions[i].z(),
                                             double(c.colors[i][0]), double(c.colors[i][1]),
                                             double(c.colors[i][2])});
  return out;
}

size_t countOf(const Surfels& s) {
  size_t n = 0;
  for (const auto& [father, list] : s) n += list.size();
  return n;
}

struct Listener {
  std::mutex mutex;
  std::vector<sensor_msgs::PointCloud2ConstPtr> full;
  std::vector<relaxed_connectivity::PaintDeltaConstPtr> deltas;
  relaxed_connectivity::PaintStatsConstPtr stats;
  size_t object_points = 0;

  template <class Predicate>
  bool waitFor(Predicate&& ready, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::WallTime::now() < end) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (ready()) return true;
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }
  /// Waits for a full cloud newer than the n-th and returns it.
  sensor_msgs::PointCloud2ConstPtr nextFull(size_t n) {
    EXPECT_TRUE(waitFor([&] { return full.size() > n; }, 10.0));
    std::lock_guard<std::mutex> lock(mutex);
    return full.back();
  }
};

/// The count N of a "save: N active surfels ..." or "load: N active surfels ..." answer.
size_t activeSurfelsIn(const std::string& message) {
  const size_t colon = message.find(": ");
  return colon == std::string::npos ? 0 : size_t(std::strtoul(message.c_str() + colon + 2, nullptr, 10));
}

template <class Service>
bool call(const std::string& name, Service& srv) {
  EXPECT_TRUE(ros::service::waitForService(name, ros::Duration(10.0))) << name;
  EXPECT_TRUE(ros::service::call(name, srv)) << name;
  return srv.response.success;
}

TEST(PaintModelServices, DeltasUndoRedoSaveLoadClearAndASecondObject) {
  ros::NodeHandle nh;
  Listener l;
  auto full_sub = nh.subscribe<sensor_msgs::PointCloud2>("surfels/painted", 10, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(l.mutex);
    l.full.push_back(m);
  });
  auto delta_sub =
      nh.subscribe<relaxed_connectivity::PaintDelta>("surfels/painted_delta", 5000, [&](const auto& m) {
        std::lock_guard<std::mutex> lock(l.mutex);
        l.deltas.push_back(m);
      });
  auto stats_sub = nh.subscribe<relaxed_connectivity::PaintStats>("paint_stats", 5, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(l.mutex);
    l.stats = m;
  });
  auto object_sub = nh.subscribe<sensor_msgs::PointCloud2>("surfels", 1, [&](const auto& m) {
    std::lock_guard<std::mutex> lock(l.mutex);
    l.object_points = m->width * m->height;
  });
  // The object from the topic plus the palette (launch argument palette:=primaries).
  const size_t palette_points =
      makePaletteCloud(readPalette(std::string(RC_SOURCE_DIR) + "/config/paint/palettes/primaries.yaml"))
          .size();
  // The straight stroke (4 s after the driver's start delay) ends as one undoable stroke.
  ASSERT_TRUE(l.waitFor([&] { return l.stats && l.stats->undo_strokes >= 1 && l.object_points > 0; }, 60.0));
  ros::WallDuration(0.5).sleep();  // deltas in flight
  sensor_msgs::PointCloud2ConstPtr painted;
  size_t n_full;
  {
    std::lock_guard<std::mutex> lock(l.mutex);
    painted = l.full.back();
    n_full = l.full.size();
    EXPECT_EQ(l.stats->paint, "acrylic");
    EXPECT_EQ(l.stats->originals, l.object_points + palette_points);
    EXPECT_GT(l.stats->children, 0u);
    EXPECT_GT(l.stats->journal_bytes, 0u);
    EXPECT_GT(l.stats->brush_ms, 0.0);
  }
  const size_t object_points = l.object_points + palette_points;

  // Undo: the board as loaded, published at once; the deltas since the painted full cloud lead there too.
  relaxed_connectivity::PaintCommand undo;
  ASSERT_TRUE(call("paint_model/undo", undo)) << undo.response.message;
  const sensor_msgs::PointCloud2ConstPtr undone = l.nextFull(n_full);
  EXPECT_EQ(undone->width * undone->height, object_points);
  {
    std::lock_guard<std::mutex> lock(l.mutex);
    Surfels state = byFather(*painted);
    size_t applied = 0;
    for (const auto& d : l.deltas) {
      if (d->header.stamp <= painted->header.stamp || d->header.stamp > undone->header.stamp) continue;
      for (uint32_t f : d->originals) state.erase(f);
      for (const auto& [f, list] : byFather(d->surfels)) state[f] = list;
      ++applied;
    }
    EXPECT_GT(applied, 0u);
    const Surfels expected = byFather(*undone);
    EXPECT_EQ(countOf(state), countOf(expected));
    EXPECT_TRUE(state == expected) << "the deltas applied to the painted cloud differ from the undone one";
    for (size_t k = 1; k < l.deltas.size(); ++k)
      EXPECT_EQ(l.deltas[k]->sequence, l.deltas[k - 1]->sequence + 1);
  }
  // Redo: the stroke's surfels again.
  relaxed_connectivity::PaintCommand redo;
  ASSERT_TRUE(call("paint_model/redo", redo)) << redo.response.message;
  const sensor_msgs::PointCloud2ConstPtr redone = l.nextFull(n_full + 1);
  EXPECT_GT(redone->width * redone->height, object_points);
  EXPECT_FALSE(call("paint_model/redo", redo));  // nothing more to redo

  // A second object while the board holds paint is refused and counted; the paint stays.
  const unsigned rejected_before = l.stats->rejected_messages;
  ros::Publisher other = nh.advertise<sensor_msgs::PointCloud2>("surfels", 1);
  SurfelCloud small;
  small.positions = {Vec3(0, 0, 0), Vec3(0.01, 0, 0), Vec3(0, 0.01, 0)};
  small.normals.assign(3, Vec3::UnitZ());
  small.frame_id = "world";
  ASSERT_TRUE(l.waitFor([&] { return other.getNumSubscribers() >= 2; }, 5.0));  // paint_model and us
  other.publish(PointCloud2Converter::toMessage(small));
  EXPECT_TRUE(l.waitFor([&] { return l.stats->rejected_messages > rejected_before; }, 5.0));

  // Save, clear, load: the saved state comes back.
  const std::string path = ::testing::TempDir() + "paint_model_services.ply";
  std::remove(path.c_str());
  relaxed_connectivity::PaintFile file;
  file.request.path = path;
  ASSERT_TRUE(call("paint_model/save", file)) << file.response.message;
  const size_t saved_surfels = activeSurfelsIn(file.response.message);
  EXPECT_GT(saved_surfels, object_points) << file.response.message;
  size_t n = l.full.size();
  relaxed_connectivity::PaintCommand clear;
  ASSERT_TRUE(call("paint_model/clear", clear)) << clear.response.message;
  EXPECT_EQ(l.nextFull(n)->width * l.nextFull(n)->height, object_points);
  n = l.full.size();
  ASSERT_TRUE(call("paint_model/load", file)) << file.response.message;
  EXPECT_EQ(activeSurfelsIn(file.response.message), saved_surfels) << file.response.message;
  // The full cloud of the loaded state (downsampling between strokes may already have merged some surfels).
  const sensor_msgs::PointCloud2ConstPtr loaded = l.nextFull(n);
  EXPECT_GT(loaded->width * loaded->height, object_points);
  // The same through the action, with progress.
  actionlib::SimpleActionClient<relaxed_connectivity::LoadPaintedStateAction> load_state(
      "paint_model/load_state", true);
  ASSERT_TRUE(load_state.waitForServer(ros::Duration(10.0)));
  relaxed_connectivity::LoadPaintedStateGoal goal;
  goal.path = path;
  std::vector<float> progress;
  load_state.sendGoal(goal, {}, {}, [&](const relaxed_connectivity::LoadPaintedStateFeedbackConstPtr& f) {
    std::lock_guard<std::mutex> lock(l.mutex);
    progress.push_back(f->progress);
  });
  ASSERT_TRUE(load_state.waitForResult(ros::Duration(20.0)));
  EXPECT_EQ(load_state.getState(), actionlib::SimpleClientGoalState::SUCCEEDED);
  EXPECT_EQ(load_state.getResult()->active_surfels, saved_surfels);
  {
    std::lock_guard<std::mutex> lock(l.mutex);
    ASSERT_GE(progress.size(), 2u);
    EXPECT_EQ(progress.back(), 1.0f);
  }
  goal.path = "/nonexistent/state.ply";
  load_state.sendGoal(goal);
  ASSERT_TRUE(load_state.waitForResult(ros::Duration(20.0)));
  EXPECT_EQ(load_state.getState(), actionlib::SimpleClientGoalState::ABORTED);
  EXPECT_FALSE(load_state.getResult()->success);
  // Bad requests change nothing and say why.
  relaxed_connectivity::PaintFile bad;
  bad.request.path = "/nonexistent/state.ply";
  EXPECT_FALSE(call("paint_model/load", bad));
  EXPECT_NE(bad.response.message.find("/nonexistent/state.ply"), std::string::npos);
  bad.request.path = std::string(RC_SOURCE_DIR) + "/config/paint/brushes/round.yaml";  // not a paint
  EXPECT_FALSE(call("paint_model/set_paint", bad));
  relaxed_connectivity::PaintFile oil;
  oil.request.path = std::string(RC_SOURCE_DIR) + "/config/paint/paints/oil.yaml";
  EXPECT_TRUE(call("paint_model/set_paint", oil)) << oil.response.message;
  EXPECT_TRUE(l.waitFor([&] { return l.stats->paint == "oil"; }, 5.0));
  relaxed_connectivity::PaintFile flat;
  flat.request.path = std::string(RC_SOURCE_DIR) + "/config/paint/brushes/flat.yaml";
  EXPECT_TRUE(call("paint_model/set_brush", flat)) << flat.response.message;
  EXPECT_TRUE(l.waitFor([&] { return l.stats->brush == "flat" && l.stats->paint == "oil"; }, 5.0));
  bad.request.path = std::string(RC_SOURCE_DIR) + "/config/paint/paints/oil.yaml";  // not a brush
  EXPECT_FALSE(call("paint_model/set_brush", bad));

  // After ~clear a new object is taken: one without normals is refused with the reason (counted), one with
  // a NaN surfel is taken without it (the drop counted), the palette beside it again.
  ASSERT_TRUE(call("paint_model/clear", clear)) << clear.response.message;
  unsigned rejected = l.stats->rejected_messages;
  SurfelCloud no_normals = small;
  no_normals.normals.clear();
  other.publish(PointCloud2Converter::toMessage(no_normals));
  EXPECT_TRUE(l.waitFor([&] { return l.stats->rejected_messages > rejected; }, 5.0));
  SurfelCloud with_nan = small;
  with_nan.positions.push_back(Vec3(std::nan(""), 0, 0));
  with_nan.normals.push_back(Vec3::UnitZ());
  other.publish(PointCloud2Converter::toMessage(with_nan));
  EXPECT_TRUE(l.waitFor([&] { return l.stats->originals == 3 + palette_points; }, 5.0)) << l.stats->originals;
  EXPECT_EQ(l.stats->dropped_surfels, 1u);
}

// dynamic_reconfigure (Paint.cfg): the settings show the loaded files; a brush change rebuilds the brush (its
// contact parameters change), one above the Verlet step limit is refused with the brush kept; a paint change
// answers with the new rate; ~set_brush shows the new file's settings.
TEST(PaintModelServices, BrushAndPaintSettingsReconfigure) {
  ros::NodeHandle nh;
  std::mutex mutex;
  relaxed_connectivity::BrushContactConstPtr contact;
  auto contact_sub = nh.subscribe<relaxed_connectivity::BrushContact>(
      "brush_contact", 10, [&](const relaxed_connectivity::BrushContactConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        contact = m;
      });
  auto latestContact = [&](double penalty, double friction, double seconds) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::WallTime::now() < end) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (contact && contact->penalty_stiffness == penalty && contact->friction == friction) return true;
      }
      ros::WallDuration(0.02).sleep();
    }
    return false;
  };
  // The flat preset's K_p and eta (config/paint/brushes/flat.yaml, set by the test before) in the contacts.
  EXPECT_TRUE(latestContact(400, 2.0, 10.0));
  ros::ServiceClient reconfigure =
      nh.serviceClient<dynamic_reconfigure::Reconfigure>("paint_model/set_parameters");
  ASSERT_TRUE(reconfigure.waitForExistence(ros::Duration(10)));
  double shown = 0;
  EXPECT_TRUE(ros::param::get("/paint_model/time_step", shown));
  EXPECT_EQ(shown, 8.0e-4);  // flat.yaml's (shown since ~set_brush), not Paint.cfg's default

  dynamic_reconfigure::Reconfigure stiffer =
      reconfigureRequest({{"penalty_stiffness", 777.0}, {"friction", 3.5}});
  ASSERT_TRUE(reconfigure.call(stiffer));
  EXPECT_EQ(doubleOf(stiffer.response.config, "penalty_stiffness"), 777.0);
  EXPECT_EQ(doubleOf(stiffer.response.config, "friction"), 3.5);
  EXPECT_TRUE(latestContact(777, 3.5, 10.0)) << "the rebuilt brush's contact parameters";

  // K_s 4000 N/m puts the Verlet step 8e-4 s above the skeleton's limit: refused, answered with 40.
  dynamic_reconfigure::Reconfigure unstable = reconfigureRequest({{"spring_stiffness", 4000.0}});
  ASSERT_TRUE(reconfigure.call(unstable));
  EXPECT_EQ(doubleOf(unstable.response.config, "spring_stiffness"), 40.0);
  // ... accepted with the implicit integrator (no step limit).
  dynamic_reconfigure::Reconfigure implicit =
      reconfigureRequest({{"spring_stiffness", 4000.0}, {"time_step", 0.0333}}, {{"integrator", 1}});
  ASSERT_TRUE(reconfigure.call(implicit));
  EXPECT_EQ(doubleOf(implicit.response.config, "spring_stiffness"), 4000.0);
  EXPECT_EQ(intOf(implicit.response.config, "integrator"), 1);
  EXPECT_TRUE(latestContact(777, 3.5, 10.0));  // still stepping

  dynamic_reconfigure::Reconfigure faster = reconfigureRequest({{"transfer_to_surface", 12.0}});
  ASSERT_TRUE(reconfigure.call(faster));
  EXPECT_EQ(doubleOf(faster.response.config, "transfer_to_surface"), 12.0);

  relaxed_connectivity::PaintFile round;
  round.request.path = std::string(RC_SOURCE_DIR) + "/config/paint/brushes/round.yaml";
  ASSERT_TRUE(call("paint_model/set_brush", round)) << round.response.message;
  EXPECT_TRUE(ros::param::get("/paint_model/time_step", shown));
  EXPECT_EQ(shown, 1.0e-3);  // round.yaml's
  int integrator = -1;
  EXPECT_TRUE(ros::param::get("/paint_model/integrator", integrator));
  EXPECT_EQ(integrator, 0);  // verlet
  EXPECT_TRUE(ros::param::get("/paint_model/penalty_stiffness", shown));
  EXPECT_EQ(shown, 400.0);
  EXPECT_TRUE(latestContact(400, 2.0, 10.0));
}

}  // namespace
}  // namespace rc

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "paint_model_services_test");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
