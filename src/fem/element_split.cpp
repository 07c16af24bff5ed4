#include "relaxed_connectivity/fem/element_split.h"

#include <algorithm>

namespace rc {

std::vector<int> sortedFaceKey(const PolyhedralMesh::Face& face) {
  std::vector<int> key = face;
  std::sort(key.begin(), key.end());
  return key;
}

ElementSides elementSides(const PolyhedralMesh::ElementFaces& faces, const std::vector<int>& side) {
  ElementSides sides;
  for (const PolyhedralMesh::Face& face : faces)
    for (int v : face) {
      sides.positive = sides.positive || side[v] > 0;
      sides.negative = sides.negative || side[v] < 0;
    }
  return sides;
}

EdgeCrossingNodes::EdgeCrossingNodes(const std::vector<double>& distance, AddNode add_node)
    : distance_(distance), add_node_(std::move(add_node)) {}

int EdgeCrossingNodes::operator()(int a, int b) {
  const auto key = std::make_pair(std::min(a, b), std::max(a, b));
  auto it = nodes_.find(key);
  if (it != nodes_.end()) return it->second;
  const double t = distance_[key.first] / (distance_[key.first] - distance_[key.second]);
  const int id = add_node_(key.first, key.second, t);
  nodes_.emplace(key, id);
  return id;
}

int EdgeCrossingNodes::find(int a, int b) const {
  auto it = nodes_.find(std::make_pair(std::min(a, b), std::max(a, b)));
  return it == nodes_.end() ? -1 : it->second;
}

FaceSplit splitFace(const PolyhedralMesh::Face& face, const std::vector<int>& side,
                    EdgeCrossingNodes& crossing, std::vector<int>* on_plane) {
  FaceSplit split;
  for (size_t k = 0; k < face.size(); ++k) {
    const int a = face[k], b = face[(k + 1) % face.size()];
    if (side[a] >= 0) split.positive.push_back(a);
    if (side[a] <= 0) split.negative.push_back(a);
    split.has_positive = split.has_positive || side[a] > 0;
    split.has_negative = split.has_negative || side[a] < 0;
    if (side[a] == 0 && on_plane) on_plane->push_back(a);
    if (side[a] * side[b] < 0) {
      const int m = crossing(a, b);
      split.positive.push_back(m);
      split.negative.push_back(m);
      if (on_plane) on_plane->push_back(m);
    }
  }
  return split;
}

ElementSplit splitElement(const PolyhedralMesh::ElementFaces& faces, const std::vector<int>& side,
                          EdgeCrossingNodes& crossing, const SectionOrder& order_section) {
  ElementSplit split;
  std::vector<int> section, on_plane;
  for (size_t f = 0; f < faces.size(); ++f) {
    on_plane.clear();
    FaceSplit halves = splitFace(faces[f], side, crossing, &on_plane);
    for (int v : on_plane)
      if (std::find(section.begin(), section.end(), v) == section.end()) section.push_back(v);
    if (!halves.has_positive && !halves.has_negative) {
      split.face_in_plane = static_cast<int>(f);
      return split;
    }
    if (halves.has_positive) {
      split.positive.push_back(std::move(halves.positive));
      split.positive_source.push_back(static_cast<int>(f));
    }
    if (halves.has_negative) {
      split.negative.push_back(std::move(halves.negative));
      split.negative_source.push_back(static_cast<int>(f));
    }
    if (halves.has_positive && halves.has_negative) split.split_faces.push_back(static_cast<int>(f));
  }
  for (int k : order_section(section)) split.section.push_back(section[k]);
  split.negative.push_back(split.section);
  split.negative_source.push_back(-1);
  split.positive.push_back(PolyhedralMesh::Face(split.section.rbegin(), split.section.rend()));
  split.positive_source.push_back(-1);
  return split;
}

std::vector<Vec3> planeSectionPoints(const PolyhedralMesh::ElementFaces& faces, const std::vector<int>& side,
                                     const std::vector<double>& distance, const std::vector<Vec3>& nodes) {
  std::vector<Vec3> points;
  for (const PolyhedralMesh::Face& face : faces)
    for (size_t k = 0; k < face.size(); ++k) {
      const int a = face[k], b = face[(k + 1) % face.size()];
      if (side[a] == 0) points.push_back(nodes[a]);
      if (side[a] * side[b] < 0) {
        const double t = distance[a] / (distance[a] - distance[b]);
        points.push_back((1.0 - t) * nodes[a] + t * nodes[b]);
      }
    }
  return points;
}

}  // namespace rc
