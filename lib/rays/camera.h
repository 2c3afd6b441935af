#pragma once
/// The pinhole camera of the `primary` ray set and of `raylab render`.
#include <string>
#include <vector>

#include "geometry/bounds.h"
#include "geometry/ray.h"

namespace raylab {

/// A pinhole camera. Image coordinates run from (0, 0), the top-left corner of the image, to
/// (W, H), the bottom-right one; pixel (i, j) has its centre at (i + 0.5, j + 0.5).
struct Camera {
  Vec3d eye;
  Vec3d forward;  ///< unit viewing direction
  Vec3d right;    ///< unit, image +x
  Vec3d up;       ///< unit, image -y (rows grow downward)
  double tan_half_fov = 0.0;  ///< tan of half the vertical field of view
};

/// The default viewing direction: the camera sits on the ray from the centre of the scene
/// toward (1, 0.6, 1.4) and looks back at the centre.
inline constexpr Vec3d kDefaultCameraFrom{1.0, 0.6, 1.4};
inline constexpr double kDefaultFovDegrees = 45.0;

/// A camera that looks at the centre of `bounds` from direction `from` (any non-zero vector; it
/// is normalised), at the distance where the bounding sphere of the box (centre, half the
/// diagonal) exactly fills the vertical field of view `fov_degrees` (in (0, 180)). World +y is
/// the image up unless `from` is parallel to it, in which case +z is. Throws InputError for an
/// empty or non-finite box.
Camera frame_camera(const Bounds3f& bounds, double fov_degrees = kDefaultFovDegrees,
                    const Vec3d& from = kDefaultCameraFrom);

/// Where an inside camera's eye lies on the segment from the box centre to the box boundary.
inline constexpr double kInsideCameraFraction = 0.9;

/// A camera inside `bounds` that looks at its centre: the eye lies in direction `from` from the
/// centre, kInsideCameraFraction of the way to the box boundary (the centre itself for a box that
/// is flat across that direction). Meant for enclosed scenes (`room:...,window=0`), whose inside
/// an outside camera cannot see. Same field of view, image up and errors as frame_camera.
Camera inside_camera(const Bounds3f& bounds, double fov_degrees = kDefaultFovDegrees,
                     const Vec3d& from = kDefaultCameraFrom);

/// Where a camera-based ray set (`camera=`) or `raylab render --camera` puts the eye.
enum class CameraPlacement { outside, inside };

/// "outside" and "inside", in the order of CameraPlacement.
const std::vector<std::string>& camera_placement_names();

/// The placement called `name` (one of camera_placement_names()); throws InputError otherwise.
CameraPlacement parse_camera_placement(const std::string& name);

/// frame_camera for CameraPlacement::outside, inside_camera for CameraPlacement::inside.
Camera placed_camera(CameraPlacement placement, const Bounds3f& bounds,
                     double fov_degrees = kDefaultFovDegrees, const Vec3d& from = kDefaultCameraFrom);

/// The ray through image point (px, py) of a W×H image (square pixels, aspect W/H): origin at
/// the eye, unit direction (rounded to float), tmin = 0, tmax = inf.
Ray camera_ray(const Camera& camera, double px, double py, int width, int height);

/// The rays through the centres of every pixel of a W×H image, in scanline order: ray i is
/// pixel (i % W, i / W).
std::vector<Ray> image_rays(const Camera& camera, int width, int height);

}  // namespace raylab
