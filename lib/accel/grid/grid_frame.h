#pragma once
/// The frame a grid is placed and walked in: scene coordinates minus an origin chosen so that
/// the translation is exact for every vertex and sphere centre. A scene far from the world
/// origin (|coordinates| much larger than its extent) is placed and walked near the frame's
/// origin, so its placement margin (grid_margin, a fraction of the coordinates' magnitude) is a
/// fraction of the scene's extent instead of its distance from the world origin; a scene near
/// the world origin keeps the world frame, bit for bit.
///
/// Only placement and the 3D-DDA use the frame. The kernels test the scene's own triangles
/// against the ray as given, so hits (t, u, v, primitive) are the same whatever the frame.
#include <memory>

#include "accel/grid/cell_triangles.h"
#include "geometry/bounds.h"
#include "geometry/ray.h"
#include "scene/scene.h"

namespace raylab {

/// Whether a frame with this origin is the world frame (no translation).
inline bool is_world_frame(const Vec3f& origin) { return origin == Vec3f(0.0f); }

struct GridFrame {
  /// Subtracted from scene coordinates; 0 on every axis for a scene near the world origin.
  Vec3f origin{0.0f};
  /// The scene in the frame: the scene itself when origin is 0, else a translated copy whose
  /// every coordinate minus origin is exact (a flat scene only).
  std::shared_ptr<const Scene> scene;

  bool is_world() const { return is_world_frame(origin); }
};

/// The frame of a grid over `scene` (flat, not instanced). Per axis, the origin is the bound
/// nearest zero when the scene lies on one side of zero at a distance of at least its extent
/// along that axis, else 0: a float v with |v| >= |origin| of the same sign is a multiple of
/// origin's ulp, and |v - origin| <= extent <= |origin| is then representable, so v - origin is
/// exact (checked on every coordinate all the same). The frame is used only where it shrinks
/// the placement margin more than fourfold; else it is the world frame.
GridFrame make_grid_frame(std::shared_ptr<const Scene> scene);

/// `ray` with its origin in the frame: o - origin, rounded once (u/2·|o - origin|, within the
/// |o| terms of dda_within_margin's bound); its direction and t-range are unchanged, so a t in
/// the frame is the same t in the world.
inline Ray in_frame(Ray ray, const Vec3f& origin) {
  ray.org = ray.org - origin;
  return ray;
}

/// Adds `origin` back to every copied triangle: copies made from the frame's scene become the
/// scene's own triangles again, exactly (the frame's translation was exact).
void to_world(CellTriangles& tris, const Vec3f& origin);

}  // namespace raylab
