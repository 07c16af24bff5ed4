#include "relaxed_connectivity/render/scene/framing_camera.h"

#include <stdexcept>

namespace rc {

Camera framingCamera(const Vec3& lo, const Vec3& hi, uint32_t width, uint32_t height, const Vec3& eye_offset,
                     double horizontal_fov) {
  if (!lo.allFinite() || !hi.allFinite()) throw std::invalid_argument("framingCamera: the box is not finite");
  if (!eye_offset.allFinite() || eye_offset.norm() == 0)
    throw std::invalid_argument("framingCamera: the eye offset is zero or not finite");
  const Vec3 centre = 0.5 * (lo + hi);
  const double extent = (hi - lo).norm();
  if (!(extent > 0)) throw std::invalid_argument("framingCamera: the box is empty (zero size)");
  Camera camera = Camera::perspective(width, height, horizontal_fov);
  camera.lookAt(centre + extent * eye_offset, centre);  // image up: world +z (or another axis along it)
  camera.validate();
  return camera;
}

}  // namespace rc
