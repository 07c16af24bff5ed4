// Writes the three stroke files the haptic_driver's replay device ships with (config/paint/strokes/), in the
// format of src/paint/stroke_file.h, for the round brush (bristles 20 mm along -z of the stylus):
//   straight.csv  press onto the horizontal plane z = 0, paint 80 mm along +x, lift off
//   spiral.csv    an outward spiral of three turns over the plane z = 0, stylus tilted towards the centre
//   edge.csv      along the top face z = 0 of a block (x < 0) over its 90-degree edge at x = z = 0 and down
//                 its side face x = 0, the stylus turning with the surface normal
//   session.csv   the paint session's demo (launch/paint_session.launch): dip into the red well of
//                 config/paint/palettes/session.yaml, a stroke along +x, dip into the blue well, two strokes
//                 (one parallel, one across), all on the plane z = 0 beside the palette
// Usage: make_strokes [OUTPUT_DIR]   (default config/paint/strokes)
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "relaxed_connectivity/paint/stroke_file.h"

namespace {

using rc::StrokeSample;
using rc::Vec3;

constexpr double kRate = 200;           // samples per second
constexpr double kPressHeight = 0.014;  // ferrule above the surface: 6 mm of a 20 mm brush pressed

double smoothstep(double u) {
  u = std::fmin(std::fmax(u, 0.0), 1.0);
  return u * u * (3 - 2 * u);
}

StrokeSample sample(double t, const Vec3& position, const Eigen::Quaterniond& q, bool paint) {
  StrokeSample s;
  s.t = t;
  s.position = position;
  s.orientation = q.normalized();
  s.buttons = paint ? 1u : 0u;
  return s;
}

// approach 0.5 s -> paint `duration` s along `path(u)`, u in [0, 1] -> lift 0.5 s.
template <class Path, class Orientation>
std::vector<StrokeSample> stroke(double duration, Path path, Orientation orientation, const Vec3& lift) {
  std::vector<StrokeSample> samples;
  const double approach = 0.5;
  const int n = int(std::lround((2 * approach + duration) * kRate));
  for (int k = 0; k <= n; ++k) {
    const double t = k / kRate;
    if (t < approach) {
      const double u = smoothstep(t / approach);
      samples.push_back(sample(t, path(0.0) + (1 - u) * lift, orientation(0.0), false));
    } else if (t <= approach + duration) {
      const double u = (t - approach) / duration;
      samples.push_back(sample(t, path(u), orientation(u), true));
    } else {
      const double u = smoothstep((t - approach - duration) / approach);
      samples.push_back(sample(t, path(1.0) + u * lift, orientation(1.0), false));
    }
  }
  return samples;
}

/// Appends `next` to `samples` after a straight travel of `travel` seconds from the last sample to the first
/// of `next` (both lifted), shifting `next` in time.
void append(std::vector<StrokeSample>* samples, const std::vector<StrokeSample>& next, double travel) {
  double t0 = 0;
  if (!samples->empty()) {
    const StrokeSample from = samples->back(), to = next.front();
    const int n = int(std::lround(travel * kRate));
    for (int k = 1; k < n; ++k) {
      const double u = smoothstep(double(k) / n);
      samples->push_back(sample(from.t + k / kRate, (1 - u) * from.position + u * to.position,
                                from.orientation.slerp(u, to.orientation), false));
    }
    t0 = from.t + travel;
  }
  for (StrokeSample s : next) {
    s.t += t0;
    samples->push_back(s);
  }
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : "config/paint/strokes";
  const Vec3 up(0, 0, 0.03);
  try {
    // Straight: 80 mm along +x in 2 s, the stylus trailing 15 degrees.
    const Eigen::Quaterniond trail(Eigen::AngleAxisd(-15 * M_PI / 180, Vec3::UnitY()));
    rc::writeStrokeFile(dir + "/straight.csv",
                        stroke(
                            2.0, [](double u) { return Vec3(-0.04 + 0.08 * u, 0, kPressHeight); },
                            [&](double) { return trail; }, up),
                        "straight stroke: press onto the plane z = 0 (ferrule at z = 14 mm), paint 80 mm "
                        "along +x in 2 s, lift\n"
                        "written by src/tools/make_strokes.cpp; format: src/paint/stroke_file.h");
    // Spiral: radius 5 -> 40 mm, three turns in 6 s, tilted 20 degrees towards the centre.
    auto spiral = [](double u) {
      const double angle = 6 * M_PI * u, r = 0.005 + 0.035 * u;
      return Vec3(r * std::cos(angle), r * std::sin(angle), kPressHeight);
    };
    auto towards_centre = [](double u) {
      const double angle = 6 * M_PI * u;
      const Vec3 tangent(-std::sin(angle), std::cos(angle), 0);
      return Eigen::Quaterniond(Eigen::AngleAxisd(20 * M_PI / 180, tangent));
    };
    rc::writeStrokeFile(dir + "/spiral.csv", stroke(6.0, spiral, towards_centre, up),
                        "spiral: three outward turns, radius 5 -> 40 mm, over the plane z = 0 in 6 s\n"
                        "written by src/tools/make_strokes.cpp; format: src/paint/stroke_file.h");
    // Edge: 40 mm along the top face, a quarter circle of radius kPressHeight around the edge, 40 mm down the
    // side; the stylus axis follows the surface normal (rotation about y from +z to +x).
    const double top = 0.04, arc = M_PI / 2 * kPressHeight, side = 0.04, length = top + arc + side;
    auto edge_angle = [=](double u) {
      return std::fmin(std::fmax((u * length - top) / kPressHeight, 0.0), M_PI / 2);
    };
    auto edge = [=](double u) {
      const double s = u * length;
      if (s <= top) return Vec3(-top + s, 0, kPressHeight);
      if (s <= top + arc) {
        const double a = edge_angle(u);
        return Vec3(kPressHeight * std::sin(a), 0, kPressHeight * std::cos(a));
      }
      return Vec3(kPressHeight, 0, -(s - top - arc));
    };
    auto edge_orientation = [=](double u) {
      return Eigen::Quaterniond(Eigen::AngleAxisd(edge_angle(u), Vec3::UnitY()));
    };
    rc::writeStrokeFile(
        dir + "/edge.csv", stroke(3.0, edge, edge_orientation, Vec3(0, 0, 0.03)),
        "across a 90-degree edge: top face z = 0 (x < 0), edge at x = z = 0, side face x = 0\n"
        "(z < 0); 40 mm on top, around the edge, 40 mm down the side in 3 s\n"
        "written by src/tools/make_strokes.cpp; format: src/paint/stroke_file.h");
    // Session: the wells of config/paint/palettes/session.yaml lie at y = -0.07 (red at x = -0.042, blue at
    // x = 0.014); each dip presses into the well and stirs a small circle for a second.
    auto dip = [&](double x) {
      return stroke(
          1.0,
          [=](double u) {
            return Vec3(x + 0.004 * std::cos(2 * M_PI * u) - 0.004, -0.07 + 0.004 * std::sin(2 * M_PI * u),
                        kPressHeight);
          },
          [&](double) { return trail; }, up);
    };
    auto line = [&](const Vec3& from, const Vec3& to, double seconds, const Eigen::Quaterniond& q) {
      return stroke(
          seconds, [=](double u) { return Vec3(from + u * (to - from) + Vec3(0, 0, kPressHeight)); },
          [=](double) { return q; }, up);
    };
    const Eigen::Quaterniond across(Eigen::AngleAxisd(0.5 * M_PI, Vec3::UnitZ()) * trail);  // stroke along +y
    std::vector<StrokeSample> session;
    append(&session, dip(-0.042), 0.5);
    append(&session, line(Vec3(-0.05, 0.03, 0), Vec3(0.05, 0.03, 0), 2.5, trail), 0.8);
    append(&session, dip(0.014), 0.8);
    append(&session, line(Vec3(-0.05, 0.06, 0), Vec3(0.05, 0.06, 0), 2.5, trail), 0.8);
    append(&session, line(Vec3(0.0, 0.0, 0), Vec3(0.0, 0.09, 0), 2.0, across), 0.8);
    rc::writeStrokeFile(
        dir + "/session.csv", session,
        "paint session: red well, stroke along +x at y = 30 mm, blue well, strokes along +x at\n"
        "y = 60 mm and along +y at x = 0 (crossing both), over the plane z = 0; palette wells at\n"
        "y = -70 mm (config/paint/palettes/session.yaml)\n"
        "written by src/tools/make_strokes.cpp; format: src/paint/stroke_file.h");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "make_strokes: %s\n", e.what());
    return 1;
  }
  std::printf("make_strokes: wrote straight.csv, spiral.csv, edge.csv, session.csv to %s\n", dir.c_str());
  return 0;
}
