#include "rays/camera.h"

#include <cmath>
#include <limits>
#include <numbers>

#include "geometry/input_error.h"

namespace raylab {

namespace {

void check_view(const Bounds3f& bounds, double fov_degrees, const Vec3d& from) {
  if (bounds.empty() || !is_finite(bounds.lo) || !is_finite(bounds.hi))
    throw InputError("camera: the scene is empty or not finite, nothing to frame");
  if (!(fov_degrees > 0.0 && fov_degrees < 180.0))
    throw InputError("camera: field of view " + std::to_string(fov_degrees) + " is outside (0, 180) degrees");
  if (!is_finite(from) || dot(from, from) == 0.0) throw InputError("camera: the viewing direction is zero");
}

/// The camera at `eye` looking along −`dir_from` (a unit vector).
Camera camera_looking_back(const Vec3d& eye, const Vec3d& dir_from, double fov_degrees) {
  Camera c;
  c.eye = eye;
  c.forward = -dir_from;
  const Vec3d world_up = std::abs(dir_from.y) > 0.999 ? Vec3d(0, 0, 1) : Vec3d(0, 1, 0);
  c.right = normalize(cross(c.forward, world_up));
  c.up = cross(c.right, c.forward);
  c.tan_half_fov = std::tan(0.5 * fov_degrees * std::numbers::pi / 180.0);
  return c;
}

}  // namespace

Camera frame_camera(const Bounds3f& bounds, double fov_degrees, const Vec3d& from) {
  check_view(bounds, fov_degrees, from);
  const Bounds3d b(Vec3d(bounds.lo), Vec3d(bounds.hi));
  const Vec3d centre = b.center();
  double radius = 0.5 * length(b.diagonal());
  if (radius == 0.0) radius = std::max(1.0, max_component(abs(centre))) * 1e-3;  // a single point
  const double half_fov = 0.5 * fov_degrees * std::numbers::pi / 180.0;
  const Vec3d dir_from = normalize(from);
  return camera_looking_back(centre + dir_from * (radius / std::sin(half_fov)), dir_from, fov_degrees);
}

Camera inside_camera(const Bounds3f& bounds, double fov_degrees, const Vec3d& from) {
  check_view(bounds, fov_degrees, from);
  const Bounds3d b(Vec3d(bounds.lo), Vec3d(bounds.hi));
  const Vec3d centre = b.center(), half = 0.5 * b.diagonal();
  const Vec3d dir_from = normalize(from);
  // The ray centre + s·dir_from leaves the box at the smallest half[a] / |dir_from[a]|.
  double to_boundary = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a)
    if (dir_from[a] != 0.0) to_boundary = std::min(to_boundary, half[a] / std::abs(dir_from[a]));
  return camera_looking_back(centre + dir_from * (kInsideCameraFraction * to_boundary), dir_from, fov_degrees);
}

Ray camera_ray(const Camera& camera, double px, double py, int width, int height) {
  const double aspect = static_cast<double>(width) / static_cast<double>(height);
  const double sx = (2.0 * px / width - 1.0) * camera.tan_half_fov * aspect;
  const double sy = (1.0 - 2.0 * py / height) * camera.tan_half_fov;
  const Vec3d d = normalize(camera.forward + camera.right * sx + camera.up * sy);
  return Ray{Vec3f(camera.eye), Vec3f(d), 0.0f, std::numeric_limits<float>::infinity()};
}

std::vector<Ray> image_rays(const Camera& camera, int width, int height) {
  std::vector<Ray> rays;
  rays.reserve(static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
  for (int j = 0; j < height; ++j)
    for (int i = 0; i < width; ++i) rays.push_back(camera_ray(camera, i + 0.5, j + 0.5, width, height));
  return rays;
}

const std::vector<std::string>& camera_placement_names() {
  static const std::vector<std::string> names{"outside", "inside"};
  return names;
}

CameraPlacement parse_camera_placement(const std::string& name) {
  if (name == "outside") return CameraPlacement::outside;
  if (name == "inside") return CameraPlacement::inside;
  throw InputError("camera placement '" + name + "': expected outside or inside");
}

Camera placed_camera(CameraPlacement placement, const Bounds3f& bounds, double fov_degrees, const Vec3d& from) {
  return placement == CameraPlacement::inside ? inside_camera(bounds, fov_degrees, from)
                                              : frame_camera(bounds, fov_degrees, from);
}

}  // namespace raylab
