#pragma once
/// SIMD versions of the ray-triangle kernels over a TrianglePacket (packed_triangles.h).
///
///   PacketKernel<Kernel>::Ray pr(ctx);                       // once per ray
///   int lane = PacketKernel<Kernel>::intersect<kAnyHit>(ctx, pr, packet, hit);
///
/// Contract: `intersect` returns the lane that the scalar Kernel, offered the packet's
/// triangles in lane order, would have reported last (the closest hit strictly before
/// ctx's current closest, the lowest lane among equal t), or -1; it updates ctx as the scalar
/// kernel would and writes that lane's hit. With kAnyHit it may return any hitting lane.
///
///  - Watertight (Woop, Benthin and Wald, JCGT 2013): every lane evaluates the same IEEE
///    operations in the same order as WatertightKernel::intersect (the build disables FMA
///    contraction), and lanes with an edge function equal to zero redo the paper's
///    double-precision fallback in scalar, so decisions, t, u and v are bit-identical.
///  - Möller-Trumbore (JGT 1997), the fast variant: fused multiply-adds, no bit-identity claim.
///  - Certified (certified_kernel.h): the edge functions and their error bound B for four
///    triangles at once, by the same IEEE operations the bound's derivation counts; lanes whose
///    edge functions surely have opposite signs are misses, every other filled lane goes, in
///    lane order, to CertifiedKernel::decide_triangle with its U, V, W and B, which certifies or
///    asks the exact path. The contract holds with "the scalar Kernel" read as "the certified
///    kernel": the reported lane is the last one that became the first hit.
#include <bit>
#include <cmath>

#include "accel/bvh/packed_triangles.h"
#include "accel/bvh/simd.h"
#include "geometry/certified_kernel.h"
#include "geometry/triangle_kernels.h"
#include "scene/scene_primitives.h"

namespace raylab {

template <class Kernel>
struct PacketKernel;

template <>
struct PacketKernel<WatertightKernel> {
  using F = simd::Float<kPacketWidth>;
  struct Ray {
    F ox, oy, oz, sx, sy, sz;
    Ray() = default;
    explicit Ray(const WatertightKernel::Context& c)
        : ox(F::broadcast(c.org[c.kx])),
          oy(F::broadcast(c.org[c.ky])),
          oz(F::broadcast(c.org[c.kz])),
          sx(F::broadcast(c.sx)),
          sy(F::broadcast(c.sy)),
          sz(F::broadcast(c.sz)) {}
  };

  template <bool kAnyHit>
  static int intersect(WatertightKernel::Context& c, const Ray& r, const TrianglePacket& p, TriangleHit& hit) {
    // a, b, d of the scalar kernel: the vertices relative to the origin, in sheared axes.
    const F az0 = F::load(p.v[0][c.kz]) - r.oz, bz0 = F::load(p.v[1][c.kz]) - r.oz, cz0 = F::load(p.v[2][c.kz]) - r.oz;
    const F ax = (F::load(p.v[0][c.kx]) - r.ox) - r.sx * az0, ay = (F::load(p.v[0][c.ky]) - r.oy) - r.sy * az0;
    const F bx = (F::load(p.v[1][c.kx]) - r.ox) - r.sx * bz0, by = (F::load(p.v[1][c.ky]) - r.oy) - r.sy * bz0;
    const F cx = (F::load(p.v[2][c.kx]) - r.ox) - r.sx * cz0, cy = (F::load(p.v[2][c.ky]) - r.oy) - r.sy * cz0;
    F U = cx * by - cy * bx;
    F V = ax * cy - ay * cx;
    F W = bx * ay - by * ax;
    const F zero = F::broadcast(0.0f);
    if (const unsigned fallback = (U == zero) | (V == zero) | (W == zero)) {
      alignas(16) float u[kPacketWidth], v[kPacketWidth], w[kPacketWidth];
      alignas(16) float lax[kPacketWidth], lay[kPacketWidth], lbx[kPacketWidth], lby[kPacketWidth],
          lcx[kPacketWidth], lcy[kPacketWidth];
      U.store(u), V.store(v), W.store(w);
      ax.store(lax), ay.store(lay), bx.store(lbx), by.store(lby), cx.store(lcx), cy.store(lcy);
      for (unsigned m = fallback; m != 0; m &= m - 1) {
        const int i = std::countr_zero(m);
        u[i] = static_cast<float>(double(lcx[i]) * double(lby[i]) - double(lcy[i]) * double(lbx[i]));
        v[i] = static_cast<float>(double(lax[i]) * double(lcy[i]) - double(lay[i]) * double(lcx[i]));
        w[i] = static_cast<float>(double(lbx[i]) * double(lay[i]) - double(lby[i]) * double(lax[i]));
      }
      U = F::load(u), V = F::load(v), W = F::load(w);
    }
    const unsigned mixed = ((U < zero) | (V < zero) | (W < zero)) & ((U > zero) | (V > zero) | (W > zero));
    const F det = U + V + W;
    unsigned ok = ~mixed & ~(det == zero) & finite(det) & ((1u << kPacketWidth) - 1);
    if (ok == 0) return -1;
    const F T = U * (r.sz * az0) + V * (r.sz * bz0) + W * (r.sz * cz0);
    const F inv_det = F::broadcast(1.0f) / det;
    const F t = T * inv_det;
    ok &= (t >= F::broadcast(c.tmin)) & (t < F::broadcast(c.tmax));
    if (ok == 0) return -1;
    alignas(16) float ts[kPacketWidth];
    t.store(ts);
    int best = std::countr_zero(ok);
    if constexpr (!kAnyHit) {
      for (unsigned m = ok & (ok - 1); m != 0; m &= m - 1) {
        const int i = std::countr_zero(m);
        if (ts[i] < ts[best]) best = i;
      }
    }
    alignas(16) float us[kPacketWidth], vs[kPacketWidth];
    (V * inv_det).store(us);
    (W * inv_det).store(vs);
    c.tmax = ts[best];
    hit = {ts[best], us[best], vs[best]};
    return best;
  }
};

template <>
struct PacketKernel<CertifiedKernel> {
  using F = simd::Float<kPacketWidth>;
  struct Ray {
    F ox, oy, oz, sx, sy;
    Ray() = default;
    explicit Ray(const CertifiedKernel::Context& c)
        : ox(F::broadcast(c.ray.org[c.kx])),
          oy(F::broadcast(c.ray.org[c.ky])),
          oz(F::broadcast(c.ray.org[c.kz])),
          sx(F::broadcast(c.sx)),
          sy(F::broadcast(c.sy)) {}
  };

  template <bool kAnyHit>
  static int intersect(CertifiedKernel::Context& c, const Ray& r, const TrianglePacket& p, TriangleHit& hit) {
    const unsigned filled = (1u << p.size()) - 1;
    if (!c.filter) {  // no float filter for this ray: every lane is decided exactly
      int last = -1;
      for (unsigned m = filled; m != 0; m &= m - 1) {
        const int i = std::countr_zero(m);
        if (CertifiedKernel::intersect(c, p.prim[i], p.vertex(i, 0), p.vertex(i, 1), p.vertex(i, 2), hit)) {
          last = i;
          if constexpr (kAnyHit) return i;
        }
      }
      return last;
    }
    const F az0 = F::load(p.v[0][c.kz]) - r.oz, bz0 = F::load(p.v[1][c.kz]) - r.oz, cz0 = F::load(p.v[2][c.kz]) - r.oz;
    const F ax = (F::load(p.v[0][c.kx]) - r.ox) - r.sx * az0, ay = (F::load(p.v[0][c.ky]) - r.oy) - r.sy * az0;
    const F bx = (F::load(p.v[1][c.kx]) - r.ox) - r.sx * bz0, by = (F::load(p.v[1][c.ky]) - r.oy) - r.sy * bz0;
    const F cx = (F::load(p.v[2][c.kx]) - r.ox) - r.sx * cz0, cy = (F::load(p.v[2][c.ky]) - r.oy) - r.sy * cz0;
    const F U = cx * by - cy * bx;
    const F V = ax * cy - ay * cx;
    const F W = bx * ay - by * ax;
    const F S = max(max(abs(ax) + abs(ay), abs(bx) + abs(by)), abs(cx) + abs(cy));
    const F Z = max(max(abs(az0), abs(bz0)), abs(cz0));
    const F B = S * (F::broadcast(14.0f * 0x1p-24f) * S + F::broadcast(32.0f * 0x1p-24f) * Z) +
                F::broadcast(0x1p-38f) * (Z * Z) + F::broadcast(0x1p-119f) * (F::broadcast(1.0f) + S + Z);
    const F nB = F::broadcast(0.0f) - B;
    const unsigned miss = ((U > B) | (V > B) | (W > B)) & ((U < nB) | (V < nB) | (W < nB));
    unsigned open = filled & ~miss;
    if (open == 0) return -1;
    alignas(16) float u[kPacketWidth], v[kPacketWidth], w[kPacketWidth], b[kPacketWidth], za[kPacketWidth],
        zb[kPacketWidth], zc[kPacketWidth];
    U.store(u), V.store(v), W.store(w), B.store(b), az0.store(za), bz0.store(zb), cz0.store(zc);
    int last = -1;
    for (; open != 0; open &= open - 1) {
      const int i = std::countr_zero(open);
      if (c.has && c.prim == p.prim[i]) continue;
      if (CertifiedKernel::decide_triangle(c, p.prim[i], p.vertex(i, 0), p.vertex(i, 1), p.vertex(i, 2), u[i], v[i], w[i],
                                           b[i], za[i], zb[i], zc[i], hit)) {
        last = i;
        if constexpr (kAnyHit) return i;
      }
    }
    return last;
  }
};

template <>
struct PacketKernel<MollerTrumboreKernel> {
  using F = simd::Float<kPacketWidth>;
  struct Ray {
    F o[3], d[3];
    Ray() = default;
    explicit Ray(const MollerTrumboreKernel::Context& c) {
      for (int a = 0; a < 3; ++a) {
        o[a] = F::broadcast(c.ray.org[a]);
        d[a] = F::broadcast(c.ray.dir[a]);
      }
    }
  };

  template <bool kAnyHit>
  static int intersect(MollerTrumboreKernel::Context& c, const Ray& r, const TrianglePacket& p, TriangleHit& hit) {
    F p0[3], e1[3], e2[3];
    for (int a = 0; a < 3; ++a) {
      p0[a] = F::load(p.v[0][a]);
      e1[a] = F::load(p.v[1][a]) - p0[a];
      e2[a] = F::load(p.v[2][a]) - p0[a];
    }
    const auto cross = [](const F* x, const F* y, F* out) {
      out[0] = fmsub(x[1], y[2], x[2] * y[1]);
      out[1] = fmsub(x[2], y[0], x[0] * y[2]);
      out[2] = fmsub(x[0], y[1], x[1] * y[0]);
    };
    const auto dot = [](const F* x, const F* y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
    // The division is deferred until a lane is known to hit (as Embree's Triangle4 test): the
    // barycentric and distance tests compare unnormalised U, V, T with sign(det) folded in,
    // against |det|, |det|·tmin and |det|·tmax.
    F pv[3], tv[3], qv[3];
    cross(r.d, e2, pv);
    const F det = dot(e1, pv);
    const F zero = F::broadcast(0.0f);
    unsigned ok = ~(det == zero) & finite(det) & ((1u << kPacketWidth) - 1);
    if (ok == 0) return -1;
    const F sign = sign_bits(det), abs_det = abs(det);
    for (int a = 0; a < 3; ++a) tv[a] = r.o[a] - p0[a];
    const F U = dot(tv, pv) ^ sign;
    cross(tv, e1, qv);
    const F V = dot(r.d, qv) ^ sign;
    ok &= (U >= zero) & (V >= zero) & (U + V <= abs_det);
    if (ok == 0) return -1;
    const F T = dot(e2, qv) ^ sign;
    ok &= (T >= abs_det * F::broadcast(c.ray.tmin)) & (T < abs_det * F::broadcast(c.tmax));
    if (ok == 0) return -1;
    const F inv_det = F::broadcast(1.0f) / abs_det;
    const F t = T * inv_det, u = U * inv_det, v = V * inv_det;
    // The product |det|·tmax may round up past T·(1/|det|)'s own rounding: the hit stays strictly
    // before the current closest, and on [tmin, ...).
    ok &= (t >= F::broadcast(c.ray.tmin)) & (t < F::broadcast(c.tmax));
    if (ok == 0) return -1;
    alignas(16) float ts[kPacketWidth], us[kPacketWidth], vs[kPacketWidth];
    t.store(ts);
    int best = std::countr_zero(ok);
    if constexpr (!kAnyHit) {
      for (unsigned m = ok & (ok - 1); m != 0; m &= m - 1) {
        const int i = std::countr_zero(m);
        if (ts[i] < ts[best]) best = i;
      }
    }
    u.store(us);
    v.store(vs);
    c.tmax = ts[best];
    hit = {ts[best], us[best], vs[best]};
    return best;
  }
};

/// Offers the `lanes` filled lanes of `packet` to PacketKernel<Kernel>, counted as a scalar loop
/// would count them (`lanes` tests, at most one hit). On a hit closer than ctx's closest,
/// writes `hit` with the lane's scene primitive id and returns true.
template <class Kernel, bool kAnyHit, class Counters>
inline bool intersect_triangle_packet(typename Kernel::Context& ctx, const typename PacketKernel<Kernel>::Ray& packet_ray,
                                      const TrianglePacket& packet, int lanes, Hit& hit, Counters& counters) {
  if constexpr (Counters::enabled)
    for (int i = lanes; i > 0; --i) counters.prim_test();
  TriangleHit th;
  const int lane = PacketKernel<Kernel>::template intersect<kAnyHit>(ctx, packet_ray, packet, th);
  if (lane < 0) return false;
  counters.prim_hit();
  set_scene_hit(hit, th, packet.prim[lane]);
  return true;
}

}  // namespace raylab
