#pragma once
/// The `kernel=certified|watertight` parameter of every accelerator that tests triangles or
/// spheres (brute has its own, which also offers mt and exact).
///
///  - certified:  CertifiedKernel (geometry/certified_kernel.h): the float test with a forward
///                error bound and an exact fallback, whose first hits equal the exact oracle's;
///                traversal is then run conservatively (each accelerator states how). The
///                default wherever the accelerator's other parameters allow it.
///  - watertight: WatertightKernel (Woop, Benthin and Wald 2013), float: the default only where
///                another parameter rules the certified kernel out (`bvh:robust=off`,
///                `grid:accept=first`).
#include <string>
#include <vector>

#include "geometry/certified_kernel.h"
#include "geometry/spec_string.h"

namespace raylab {

enum class KernelChoice { watertight, certified };

/// `default_doc` is the default as listed: "certified", or a rule where another parameter decides.
inline ParamDoc kernel_param_doc(std::string default_doc = "certified") {
  return {"kernel", std::move(default_doc),
          "certified (float with a forward error bound and an exact CGAL fallback: the exact oracle's first hits) | "
          "watertight (Woop et al. 2013, float)"};
}

inline const char* kernel_choice_name(KernelChoice k) {
  return k == KernelChoice::certified ? "certified" : "watertight";
}

/// `kernel=`, or `fallback` when the spec does not set it.
inline KernelChoice read_kernel_choice(SpecReader& r, KernelChoice fallback = KernelChoice::certified) {
  return r.get_choice("kernel", kernel_choice_name(fallback), {"certified", "watertight"}) == "certified"
             ? KernelChoice::certified
             : KernelChoice::watertight;
}

/// The closest-hit bound a traversal starts from: tmax, raised for the certified kernel as its
/// closest() raises every bound (CertifiedKernel::reach_of), so that no box or plane entry
/// computed within rounding of tmax is pruned.
template <class Kernel>
inline float initial_closest(const Ray& ray) {
  if constexpr (std::is_same_v<Kernel, CertifiedKernel>) return CertifiedKernel::reach_of(ray.tmax);
  else return ray.tmax;
}

/// The ray a traversal tests its root box with: tmax raised as initial_closest().
template <class Kernel>
inline Ray traversal_ray(const Ray& ray) {
  Ray r = ray;
  r.tmax = initial_closest<Kernel>(ray);
  return r;
}

}  // namespace raylab
