// The point-sampled brush surface (thesis 5.4): surfels sampled on the brush's rest shape, carrying paint,
// and deformed with the skeleton by linear blend skinning. Each skeleton node gets a frame: handle points the
// device pose, an active mass the best-fit rotation of its springs (rest -> current) and its position.
#pragma once

#include <array>
#include <vector>

#include "relaxed_connectivity/paint/brush_skeleton.h"
#include "relaxed_connectivity/paint/paint_state.h"

namespace rc {

class BrushSkin {
 public:
  static constexpr int kInfluences = 4;  ///< skeleton nodes blended per surfel

  /// Samples the skin of `preset` at its surfel_spacing (round: a cone-like surface of revolution; flat: a
  /// flattened one) and binds it to `skeleton`'s rest shape.
  BrushSkin(const BrushPreset& preset, const BrushSkeleton& skeleton);

  size_t size() const { return rest_positions_.size(); }
  const std::vector<Vec3>& restPositions() const { return rest_positions_; }  ///< brush frame
  const std::vector<Vec3>& restNormals() const { return rest_normals_; }
  double radius() const { return radius_; }  ///< surfel radius (covers the sampling)

  /// Deforms the skin with the skeleton's current state (world frame).
  void update(const BrushSkeleton& skeleton);
  const std::vector<Vec3>& positions() const { return positions_; }
  const std::vector<Vec3>& normals() const { return normals_; }

  /// Paint on the brush, per surfel (the paint model exchanges its wet part, 5.5; brush paint never dries).
  std::vector<PaintState> paint;

  /// The skin as a surfel cloud (positions, normals, radii, colours of the wet paint) in the world frame.
  SurfelCloud cloud() const;

 private:
  std::vector<Vec3> rest_positions_, rest_normals_;
  std::vector<std::array<int, kInfluences>> nodes_;
  std::vector<std::array<double, kInfluences>> weights_;
  std::vector<Vec3> positions_, normals_;
  std::vector<std::vector<int>> node_neighbours_;  // skeleton nodes joined by a spring
  std::vector<Eigen::Matrix3d> rotations_;
  double radius_ = 0;
};

}  // namespace rc
