#include "relaxed_connectivity/mesh/fast_winding_number.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace rc {

FastWindingNumber::FastWindingNumber(const TriangleMesh& mesh) : mesh_(mesh) {
  const std::vector<Vec3>& v = mesh.vertices.positions;
  const size_t n = mesh.triangles.size();
  order_.resize(n);
  centroids_.resize(n);
  normals_.resize(n);
  for (size_t t = 0; t < n; ++t) {
    const Triangle& tri = mesh.triangles[t];
    order_[t] = uint32_t(t);
    centroids_[t] = (v[tri[0]] + v[tri[1]] + v[tri[2]]) / 3.0;
    normals_[t] = 0.5 * (v[tri[1]] - v[tri[0]]).cross(v[tri[2]] - v[tri[0]]);
  }
  nodes_.reserve(2 * n / kLeafSize + 2);
  build(0, n);
}

double FastWindingNumber::operator()(const Vec3& p) const {
  const std::vector<Vec3>& v = mesh_.vertices.positions;
  double total = 0.0;
  uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[stack[--top]];
    const Vec3 r = node.center - p;
    const double dist2 = r.squaredNorm();
    if (dist2 > kFarFactor * kFarFactor * node.radius * node.radius) {
      total += r.dot(node.normal) / (dist2 * std::sqrt(dist2));
    } else if (node.left == 0) {
      for (uint32_t k = node.begin; k < node.end; ++k) {
        const Triangle& t = mesh_.triangles[order_[k]];
        const Vec3 a = v[t[0]] - p, b = v[t[1]] - p, c = v[t[2]] - p;
        const double la = a.norm(), lb = b.norm(), lc = c.norm();
        const double num = a.dot(b.cross(c));
        const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
        total += 2.0 * std::atan2(num, den);
      }
    } else {
      stack[top++] = node.left;
      stack[top++] = node.right;
    }
  }
  return total / (4.0 * M_PI);
}

uint32_t FastWindingNumber::build(size_t begin, size_t end) {
  const uint32_t index = uint32_t(nodes_.size());
  nodes_.emplace_back();
  Node node;
  node.begin = uint32_t(begin);
  node.end = uint32_t(end);
  double area = 0.0;
  Vec3 weighted = Vec3::Zero(), lo = centroids_[order_[begin]], hi = lo;
  for (size_t k = begin; k < end; ++k) {
    const uint32_t t = order_[k];
    const double a = normals_[t].norm();
    area += a;
    weighted += a * centroids_[t];
    node.normal += normals_[t];
    lo = lo.cwiseMin(centroids_[t]);
    hi = hi.cwiseMax(centroids_[t]);
  }
  node.center = area > 0 ? Vec3(weighted / area) : Vec3(0.5 * (lo + hi));
  const std::vector<Vec3>& v = mesh_.vertices.positions;
  for (size_t k = begin; k < end; ++k)
    for (uint32_t vertex : mesh_.triangles[order_[k]])
      node.radius = std::max(node.radius, (v[vertex] - node.center).norm());
  if (end - begin > kLeafSize) {
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const size_t mid = (begin + end) / 2;
    std::nth_element(order_.begin() + long(begin), order_.begin() + long(mid), order_.begin() + long(end),
                     [&](uint32_t a, uint32_t b) { return centroids_[a][axis] < centroids_[b][axis]; });
    node.left = build(begin, mid);
    node.right = build(mid, end);
  }
  nodes_[index] = node;
  return index;
}

}  // namespace rc
