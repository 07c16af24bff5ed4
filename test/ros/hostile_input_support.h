// Hostile PointCloud2 messages made from a valid one, and a /diagnostics watcher reading a node's per-input
// accepted / rejected counts (NodeDiagnostics), for the bad-input rostests of the nodes (issue 24).
#pragma once

#include <diagnostic_msgs/DiagnosticArray.h>
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>

#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace rc::test {

struct HostileCloud {
  std::string what;
  sensor_msgs::PointCloud2 msg;
};

/// Offset of the float32 field `name` in `msg` (throws if absent).
inline uint32_t fieldOffset(const sensor_msgs::PointCloud2& msg, const std::string& name) {
  for (const auto& f : msg.fields)
    if (f.name == name) return f.offset;
  throw std::invalid_argument("no field " + name);
}

/// Malformed and hostile variants of `valid` (a little-endian cloud with float32 x, y, z and at least two
/// points), each stamped `stamp` unless it is about stamps: no points, no fields, every position NaN, one
/// infinite coordinate, data one byte short, a width of 2^31 over the same data, row_step * height
/// overflowing 32 bits, big-endian, a duplicate field, a field beyond point_step, an unknown frame, and a
/// stamp older than `older_than` (the node's current input).
inline std::vector<HostileCloud> hostileClouds(const sensor_msgs::PointCloud2& valid, const ros::Time& stamp,
                                               const ros::Time& older_than) {
  std::vector<HostileCloud> out;
  auto variant = [&](const std::string& what) -> sensor_msgs::PointCloud2& {
    out.push_back({what, valid});
    out.back().msg.header.stamp = stamp;
    return out.back().msg;
  };
  const size_t points = size_t(valid.width) * valid.height;
  auto setFloat = [](sensor_msgs::PointCloud2& m, size_t point, uint32_t offset, float value) {
    std::memcpy(m.data.data() + point * m.point_step + offset, &value, sizeof(float));
  };
  {
    auto& m = variant("no points");
    m.width = 0, m.height = 1, m.row_step = 0, m.data.clear();
  }
  {
    auto& m = variant("no fields");
    m.fields.clear();
  }
  {
    auto& m = variant("every position NaN");
    for (size_t p = 0; p < points; ++p)
      for (const char* axis : {"x", "y", "z"})
        setFloat(m, p, fieldOffset(m, axis), std::numeric_limits<float>::quiet_NaN());
  }
  {
    auto& m = variant("one infinite coordinate");
    setFloat(m, 0, fieldOffset(m, "y"), std::numeric_limits<float>::infinity());
  }
  {
    auto& m = variant("data one byte short");
    m.data.pop_back();
  }
  {
    auto& m = variant("width 2^31 over the same data");
    m.width = 1u << 31, m.height = 1;
  }
  {
    auto& m = variant("row_step * height overflowing 32 bits");
    m.height = 1u << 16;
    m.row_step = (1u << 16) + 0;  // 2^16 * 2^16 = 2^32 wraps to 0 in 32 bits
    m.width = m.row_step / m.point_step;
    m.data.clear();
  }
  {
    auto& m = variant("big-endian");
    m.is_bigendian = true;
  }
  {
    auto& m = variant("duplicate field x");
    m.fields.push_back(m.fields.front());
  }
  {
    auto& m = variant("a field beyond point_step");
    sensor_msgs::PointField f;
    f.name = "beyond", f.offset = m.point_step, f.datatype = sensor_msgs::PointField::FLOAT32, f.count = 1;
    m.fields.push_back(f);
  }
  {
    auto& m = variant("unknown frame");
    m.header.frame_id = "no_such_frame";
  }
  {
    auto& m = variant("stamp older than the current input");
    m.header.stamp = older_than - ros::Duration(1.0);
    setFloat(m, 0, fieldOffset(m, "z"), 0.5f);  // other data: not the same message again
  }
  return out;
}

/// Reads the NodeDiagnostics statuses ("<node>: input <topic>" with accepted / rejected counts, and the
/// nodes' own tasks) from /diagnostics.
class InputDiagnostics {
 public:
  struct Counts {
    long accepted = -1, rejected = -1;
    std::string last_rejection;
    std::map<std::string, std::string> values;  // every key of the status
    long number(const std::string& key) const {
      auto it = values.find(key);
      return it == values.end() ? -1 : std::stol(it->second);
    }
  };

  InputDiagnostics() {
    sub_ = ros::NodeHandle().subscribe<diagnostic_msgs::DiagnosticArray>(
        "/diagnostics", 100, [this](const diagnostic_msgs::DiagnosticArrayConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          for (const auto& s : m->status) {
            Counts c;
            for (const auto& kv : s.values) {
              if (kv.key == "accepted") c.accepted = std::stol(kv.value);
              if (kv.key == "rejected") c.rejected = std::stol(kv.value);
              if (kv.key == "last rejection") c.last_rejection = kv.value;
              c.values[kv.key] = kv.value;
            }
            latest_[s.name] = c;
          }
        });
  }

  /// Spins until the status `name` satisfies `done` (up to `seconds`); returns its last counts.
  Counts waitFor(const std::string& name, const std::function<bool(const Counts&)>& done,
                 double seconds = 8.0) {
    const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds);
    Counts last;
    while (ros::WallTime::now() < end && ros::ok()) {
      ros::spinOnce();
      {
        std::lock_guard<std::mutex> lock(mutex_);
        auto it = latest_.find(name);
        if (it != latest_.end()) {
          last = it->second;
          if (done(last)) return last;
        }
      }
      ros::WallDuration(0.02).sleep();
    }
    std::string names;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [n, c] : latest_) names += " '" + n + "'";
    }
    ADD_FAILURE() << "diagnostics status '" << name << "' did not reach the expected counts within "
                  << seconds << " s (last: accepted " << last.accepted << ", rejected " << last.rejected
                  << "); statuses seen:" << names;
    return last;
  }

 private:
  ros::Subscriber sub_;
  std::mutex mutex_;
  std::map<std::string, Counts> latest_;
};

}  // namespace rc::test
