#pragma once
/// SIMD versions of the ray-triangle kernels over a TrianglePacket (packed_triangles.h).
///
///   PacketKernel<Kernel>::Ray pr(ctx);                       // once per ray
///   int lane = PacketKernel<Kernel>::intersect<kAnyHit>(ctx, pr, packet, hit);
///   int lane = PacketKernel<Kernel>::intersect_lanes<kAnyHit, 8>(ctx, pr, &packets[i], hit);
///
/// intersect_lanes<kAnyHit, 8> (every kernel here) tests two consecutive packets as one 8-lane
/// packet (lane 4k + i is lane i of packet k), one AVX test where a leaf holds two.
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
///  - Certified (certified_kernel.h): the edge functions and their error bound B for all lanes
///    at once, by the same IEEE operations the bound's derivation counts; lanes whose edge
///    functions surely have opposite signs are misses. For the others, CertifiedKernel::
///    depth_bounds' float enclosure of t, computed for all lanes with its operations, rejects
///    the lanes surely before tmin or after the current first hit. A lane left alone whose
///    enclosure is the plane crossing's and lies in [tmin, tmax], before the current first hit
///    (with kAnyHit: any such lane), is installed at once, as decide_crossing would. Otherwise
///    the rest go, nearest lower bound first (lane order with kAnyHit), to CertifiedKernel::
///    decide_crossing (the enclosure is the plane crossing's) or decide_triangle, which certify
///    or ask the double stage and the exact path, and each new first hit drops the lanes whose
///    lower bound lies beyond it.
///    The contract holds with "the scalar Kernel" read as "the certified kernel" (which does not
///    depend on the order in which a ray's candidates are offered): the reported lane is the
///    last one that became the first hit.
#include <bit>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "accel/bvh/packed_triangles.h"
#include "accel/bvh/simd.h"
#include "geometry/certified_kernel.h"
#include "geometry/triangle_kernels.h"
#include "scene/scene_primitives.h"

namespace raylab {

/// Vertex k, axis a of the kLanes lanes of the kLanes / kPacketWidth consecutive packets from `p`.
template <int kLanes>
[[gnu::always_inline]] inline simd::Float<kLanes> load_lanes(const TrianglePacket* p, int k, int a) {
  static_assert(kLanes == kPacketWidth || kLanes == 2 * kPacketWidth);
  if constexpr (kLanes == kPacketWidth) return simd::Float<kLanes>::load(p->v[k][a]);
  else return simd::Float<kLanes>::load_halves(p[0].v[k][a], p[1].v[k][a]);
}

/// The lane of `ok` (nonempty) with the smallest t, the lowest among equal ones; any lane of
/// `ok` with kAnyHit.
template <bool kAnyHit>
[[gnu::always_inline]] inline int closest_lane(unsigned ok, const float* ts) {
  int best = std::countr_zero(ok);
  if constexpr (!kAnyHit) {
    for (unsigned m = ok & (ok - 1); m != 0; m &= m - 1) {
      const int i = std::countr_zero(m);
      if (ts[i] < ts[best]) best = i;
    }
  }
  return best;
}

template <class Kernel>
struct PacketKernel;

template <>
struct PacketKernel<WatertightKernel> {
  /// The context's origin and shear in its sheared axis order, broadcast at each test.
  struct Ray {
    float ox, oy, oz, sx, sy, sz;
    Ray() = default;
    [[gnu::always_inline]] explicit Ray(const WatertightKernel::Context& c)
        : ox(c.org[c.kx]), oy(c.org[c.ky]), oz(c.org[c.kz]), sx(c.sx), sy(c.sy), sz(c.sz) {}
  };

  template <bool kAnyHit>
  static int intersect(WatertightKernel::Context& c, const Ray& r, const TrianglePacket& p, TriangleHit& hit) {
    return intersect_lanes<kAnyHit, kPacketWidth>(c, r, &p, hit);
  }

  /// The kLanes lanes of the kLanes / kPacketWidth consecutive packets from `p`, in order.
  template <bool kAnyHit, int kLanes>
  static int intersect_lanes(WatertightKernel::Context& c, const Ray& r, const TrianglePacket* p, TriangleHit& hit) {
    using F = simd::Float<kLanes>;
    const F ox = F::broadcast(r.ox), oy = F::broadcast(r.oy), oz = F::broadcast(r.oz);
    const F sx = F::broadcast(r.sx), sy = F::broadcast(r.sy), sz = F::broadcast(r.sz);
    // a, b, d of the scalar kernel: the vertices relative to the origin, in sheared axes.
    const F az0 = load_lanes<kLanes>(p, 0, c.kz) - oz, bz0 = load_lanes<kLanes>(p, 1, c.kz) - oz, cz0 = load_lanes<kLanes>(p, 2, c.kz) - oz;
    const F ax = (load_lanes<kLanes>(p, 0, c.kx) - ox) - sx * az0, ay = (load_lanes<kLanes>(p, 0, c.ky) - oy) - sy * az0;
    const F bx = (load_lanes<kLanes>(p, 1, c.kx) - ox) - sx * bz0, by = (load_lanes<kLanes>(p, 1, c.ky) - oy) - sy * bz0;
    const F cx = (load_lanes<kLanes>(p, 2, c.kx) - ox) - sx * cz0, cy = (load_lanes<kLanes>(p, 2, c.ky) - oy) - sy * cz0;
    F U = cx * by - cy * bx;
    F V = ax * cy - ay * cx;
    F W = bx * ay - by * ax;
    const F zero = F::broadcast(0.0f);
    if (const unsigned fallback = (U == zero) | (V == zero) | (W == zero)) {
      alignas(32) float u[kLanes], v[kLanes], w[kLanes];
      alignas(32) float lax[kLanes], lay[kLanes], lbx[kLanes], lby[kLanes], lcx[kLanes], lcy[kLanes];
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
    // The scalar kernel's sign test, (U < 0 || V < 0 || W < 0) && (U > 0 || V > 0 || W > 0), by
    // the least and greatest of U, V, W: the same on every lane without a NaN, and a lane with one
    // has det = NaN, which both reject.
    const unsigned mixed = (min(min(U, V), W) < zero) & (max(max(U, V), W) > zero);
    const F det = U + V + W;
    unsigned ok = ~mixed & ~(det == zero) & finite(det) & ((1u << kLanes) - 1);
    if (ok == 0) return -1;
    const F T = U * (sz * az0) + V * (sz * bz0) + W * (sz * cz0);
    const F inv_det = F::broadcast(1.0f) / det;
    const F t = T * inv_det;
    ok &= (t >= F::broadcast(c.tmin)) & (t < F::broadcast(c.tmax));
    if (ok == 0) return -1;
    alignas(32) float ts[kLanes];
    t.store(ts);
    const int best = closest_lane<kAnyHit>(ok, ts);
    alignas(32) float us[kLanes], vs[kLanes];
    (V * inv_det).store(us);
    (W * inv_det).store(vs);
    c.tmax = ts[best];
    hit = {ts[best], us[best], vs[best]};
    return best;
  }
};

template <>
struct PacketKernel<CertifiedKernel> {
  /// The context's origin and shear in its sheared axis order, broadcast at each test.
  struct Ray {
    float ox, oy, oz, sx, sy, sz;
    Ray() = default;
    [[gnu::always_inline]] explicit Ray(const CertifiedKernel::Context& c)
        : ox(c.ray.org[c.kx]), oy(c.ray.org[c.ky]), oz(c.ray.org[c.kz]), sx(c.sx), sy(c.sy), sz(c.sz) {}
  };

  template <bool kAnyHit>
  static int intersect(CertifiedKernel::Context& c, const Ray& r, const TrianglePacket& p, TriangleHit& hit) {
    return intersect_lanes<kAnyHit, kPacketWidth>(c, r, &p, hit);
  }

  /// The kLanes lanes of the kLanes / kPacketWidth consecutive packets from `p`, in the order
  /// described below. The float filter and the depth cull are inline and frameless; a packet
  /// they leave open goes to install_lane (one certified crossing) or decide_open_lanes, out of
  /// line (most packets a ray is offered are misses).
  template <bool kAnyHit, int kLanes>
  static int intersect_lanes(CertifiedKernel::Context& c, const Ray& r, const TrianglePacket* p, TriangleHit& hit) {
    static_assert(kLanes == kPacketWidth || kLanes == 2 * kPacketWidth);
    using F = simd::Float<kLanes>;
    if (!c.filter) return decide_unfiltered<kAnyHit, kLanes>(c, p, hit);
    const F ox = F::broadcast(r.ox), oy = F::broadcast(r.oy), oz = F::broadcast(r.oz);
    const F sx = F::broadcast(r.sx), sy = F::broadcast(r.sy);
    const F px = load_lanes<kLanes>(p, 0, c.kx);
    const F az0 = load_lanes<kLanes>(p, 0, c.kz) - oz, bz0 = load_lanes<kLanes>(p, 1, c.kz) - oz,
            cz0 = load_lanes<kLanes>(p, 2, c.kz) - oz;
    const F ax = (px - ox) - sx * az0, ay = (load_lanes<kLanes>(p, 0, c.ky) - oy) - sy * az0;
    const F bx = (load_lanes<kLanes>(p, 1, c.kx) - ox) - sx * bz0, by = (load_lanes<kLanes>(p, 1, c.ky) - oy) - sy * bz0;
    const F cx = (load_lanes<kLanes>(p, 2, c.kx) - ox) - sx * cz0, cy = (load_lanes<kLanes>(p, 2, c.ky) - oy) - sy * cz0;
    const F U = cx * by - cy * bx;
    const F V = ax * cy - ay * cx;
    const F W = bx * ay - by * ax;
    // CertifiedKernel::edge_bound(2·M, Z) with M = max_q max(|Q̂x|, |Q̂y|), since S <= 2·M: seven
    // max-abs operations instead of sixteen for S and Z; the factor 2 is folded into the constants
    // (exactly), and 2^-119·(1 + 2M + Z) <= 2^-118·(1/2 + M + Z).
    const F M = max_abs(max_abs(max_abs(ax, ay), max_abs(bx, by)), max_abs(cx, cy));
    const F Z = max_abs(max_abs(az0, bz0), cz0);
    const F B = M * (F::broadcast(28.0f * 0x1p-23f) * M + F::broadcast(32.0f * 0x1p-23f) * Z) +
                F::broadcast(0x1p-38f) * (Z * Z) + F::broadcast(0x1p-118f) * (F::broadcast(0.5f) + M + Z);
    // Open: not surely missed (two edge functions of certain opposite signs) and in use: unused
    // lanes have NaN vertices, which no scene has (loaders reject non-finite coordinates; scene
    // specs produce finite ones, or infinite past the float range, never NaN).
    const unsigned open = ~((max(max(U, V), W) > B) & (min(min(U, V), W) < F::broadcast(0.0f) - B)) & (px == px);
    if (open == 0) return -1;
    // Most packets the cull leaves open hold one lane, a crossing its enclosure certifies (an
    // occluder, or a closest hit before the current one). Inline, this took the certified 8-wide
    // BVH from 1.09-1.13x the watertight kernel's time to 1.02-1.09x on the elephant moved 10^4
    // from the origin, and from 1.08-1.14x to 1.01-1.13x on the camel (bench_bvh, primary,
    // diffuse and shadow rays, medians of 5 processes each).
    if (!c.cull) return decide_open_lanes<kAnyHit, kLanes>(c, p, U, V, W, B, az0, bz0, cz0, open, nullptr, hit);
    const DepthCull<kLanes> d(c, r, U, V, W, B, az0, bz0, cz0, open);
    if (d.open == 0) return -1;
    const unsigned sure = d.certified_in_range(c);
    if (sure != 0 && (kAnyHit || (sure == d.open && std::has_single_bit(sure))))
      if (const int i = std::countr_zero(sure); d.comes_first(c, p, i)) return install_lane(c, p, U, V, W, d, i, hit);
    return decide_open_lanes<kAnyHit, kLanes>(c, p, U, V, W, B, az0, bz0, cz0, d.open, &d, hit);
  }

 private:
  /// CertifiedKernel::depth_bounds, lane by lane with the same operations (requires c.cull), and
  /// the lanes of `open` it leaves: bounds on the exact t of every lane, the plane crossing's
  /// where the edge functions certify a crossing of the interior (t_lo, t_hi, with the estimate
  /// t: the lanes of `crossing`), else the vertices' depth range (its lower ends range_lo).
  template <int kLanes>
  struct DepthCull {
    using F = simd::Float<kLanes>;
    F t, t_lo, t_hi, range_lo;
    unsigned open = 0, crossing = 0;

    [[gnu::always_inline]] DepthCull(const CertifiedKernel::Context& c, const Ray& r, F U, F V, F W, F B, F az0, F bz0,
                                     F cz0, unsigned open_lanes) {
      const F nB = F::broadcast(0.0f) - B;
      const F sz = F::broadcast(r.sz);
      const F za = az0 * sz, zb = bz0 * sz, zc = cz0 * sz;
      const F zmin = min(min(za, zb), zc), zmax = max(max(za, zb), zc);
      const F aU = abs(U), aV = abs(V), aW = abs(W), D = aU + aV + aW;
      const F tiny = F::broadcast(0x1p-60f), big = F::broadcast(0x1p127f);
      const unsigned certain = (min(min(U, V), W) > B) | (max(max(U, V), W) < nB);
      const F inv_D = F::broadcast(1.0f) / D;
      t = (aU * za + aV * zb + aW * zc) * inv_D;
      const F E = F::broadcast(7.0f) * (B * inv_D) * (zmax - zmin) + F::broadcast(0x1p-19f) * max(abs(zmin), abs(zmax)) + tiny;
      crossing = open_lanes & certain & (D >= F::broadcast(16.0f) * B) & (D >= tiny) & (D <= F::broadcast(0x1p120f)) &
                 (abs(t) <= big) & (E <= big);
      range_lo = zmin - (F::broadcast(0x1p-20f) * abs(zmin) + tiny);
      const F range_hi = zmax + (F::broadcast(0x1p-20f) * abs(zmax) + tiny);
      t_lo = t - E, t_hi = t + E;
      const F tmin = F::broadcast(c.ray.tmin), upper = F::broadcast(c.upper);
      open = open_lanes & ~((crossing & ((t_hi < tmin) | (t_lo > upper))) |
                            (~crossing & ((range_hi < tmin) | (range_lo > upper))));
      crossing &= open;
    }

    /// The crossing lanes whose enclosure lies in [tmin, tmax].
    [[gnu::always_inline]] unsigned certified_in_range(const CertifiedKernel::Context& c) const {
      return crossing & (t_lo >= F::broadcast(c.ray.tmin)) & (t_hi <= F::broadcast(c.ray.tmax));
    }

    /// Lane i (one of certified_in_range) surely comes before the current first hit, if any:
    /// decide_crossing would install it.
    [[gnu::always_inline]] bool comes_first(const CertifiedKernel::Context& c, const TrianglePacket* p, int i) const {
      if (!c.has) return true;
      if (c.prim == p[i / kPacketWidth].prim[i % kPacketWidth]) return false;
      alignas(32) float hi[kLanes];
      t_hi.store(hi);
      return double(hi[i]) < c.lo;
    }
  };

  /// Installs lane i, a crossing that DepthCull certified and comes_first, as decide_crossing
  /// does; returns i.
  template <int kLanes>
  [[gnu::noinline]] static int install_lane(CertifiedKernel::Context& c, const TrianglePacket* p, simd::Float<kLanes> U,
                                            simd::Float<kLanes> V, simd::Float<kLanes> W, const DepthCull<kLanes>& d,
                                            int i, TriangleHit& hit) {
    alignas(32) float u[kLanes], v[kLanes], w[kLanes], lo[kLanes], hi[kLanes], t[kLanes];
    U.store(u), V.store(v), W.store(w), d.t_lo.store(lo), d.t_hi.store(hi), d.t.store(t);
    const TrianglePacket& q = p[i / kPacketWidth];
    const int l = i % kPacketWidth;
    CertifiedKernel::install_crossing(c, q.prim[l], q.vertex(l, 0), q.vertex(l, 1), q.vertex(l, 2), u[i], v[i], w[i],
                                      lo[i], hi[i], t[i], hit);
    return i;
  }

  /// The lanes in use of the kLanes / kPacketWidth packets from `p`.
  template <int kLanes>
  static unsigned filled_lanes(const TrianglePacket* p) {
    unsigned m = (1u << p[0].size()) - 1;
    if constexpr (kLanes == 2 * kPacketWidth) m |= ((1u << p[1].size()) - 1) << kPacketWidth;
    return m;
  }

  /// A ray without the float filter: every lane is decided by the scalar kernel (the double
  /// stage and the exact path).
  template <bool kAnyHit, int kLanes>
  [[gnu::noinline]] static int decide_unfiltered(CertifiedKernel::Context& c, const TrianglePacket* p, TriangleHit& hit) {
    int last = -1;
    for (unsigned m = filled_lanes<kLanes>(p); m != 0; m &= m - 1) {
      const int i = std::countr_zero(m);
      const TrianglePacket& q = p[i / kPacketWidth];
      const int l = i % kPacketWidth;
      if (CertifiedKernel::intersect(c, q.prim[l], q.vertex(l, 0), q.vertex(l, 1), q.vertex(l, 2), hit)) {
        last = i;
        if constexpr (kAnyHit) return i;
      }
    }
    return last;
  }

  /// The lanes of `open` (a nonempty set of lanes in use that neither the float filter nor the
  /// depth cull `d` rejected; d is null without c.cull), from the filter's edge functions U, V, W,
  /// their bound B and the vertices' az, bz, cz.
  template <bool kAnyHit, int kLanes>
  [[gnu::noinline]] static int decide_open_lanes(CertifiedKernel::Context& c, const TrianglePacket* p,
                                                 simd::Float<kLanes> U, simd::Float<kLanes> V, simd::Float<kLanes> W,
                                                 simd::Float<kLanes> B, simd::Float<kLanes> az0,
                                                 simd::Float<kLanes> bz0, simd::Float<kLanes> cz0, unsigned open,
                                                 const DepthCull<kLanes>* d, TriangleHit& hit) {
    const auto prim = [p](int i) { return p[i / kPacketWidth].prim[i % kPacketWidth]; };
    const auto vertex = [p](int i, int k) { return p[i / kPacketWidth].vertex(i % kPacketWidth, k); };
    // The depth cull's bounds (the lower ends of the lanes that are not crossings, lo, are read
    // only to order the lanes: not with kAnyHit). lower() picks a lane's at each read, rather than
    // storing tl over lo (a scalar store into a vector just stored stalls the reads).
    alignas(32) float lo[kLanes], tl[kLanes], th[kLanes], ts[kLanes];
    unsigned crossing = 0;
    if (d) {
      crossing = d->crossing;
      if constexpr (!kAnyHit) d->range_lo.store(lo);
      if (crossing != 0) d->t_lo.store(tl), d->t_hi.store(th), d->t.store(ts);
    } else if constexpr (!kAnyHit) {
      for (int i = 0; i < kLanes; ++i) lo[i] = -INFINITY;
    }
    alignas(32) float u[kLanes], v[kLanes], w[kLanes], b[kLanes], za[kLanes], zb[kLanes], zc[kLanes];
    U.store(u), V.store(v), W.store(w), B.store(b), az0.store(za), bz0.store(zb), cz0.store(zc);
    // The open lanes, nearest lower depth bound first (lowest lane among equal ones; with kAnyHit
    // in lane order): once a lane becomes the first hit, the lanes whose lower bound lies beyond
    // it are dropped without the double stage.
    const auto lower = [&](int i) { return (crossing >> i) & 1u ? tl[i] : lo[i]; };
    int last = -1;
    while (open != 0) {
      int i = std::countr_zero(open);
      if constexpr (!kAnyHit)
        for (unsigned m = open & (open - 1); m != 0; m &= m - 1)
          if (lower(std::countr_zero(m)) < lower(i)) i = std::countr_zero(m);
      open &= ~(1u << i);
      if (c.has && c.prim == prim(i)) continue;
      const bool won =
          (crossing >> i) & 1u
              ? CertifiedKernel::decide_crossing(c, prim(i), vertex(i, 0), vertex(i, 1), vertex(i, 2), u[i], v[i], w[i],
                                                 b[i], za[i], zb[i], zc[i], tl[i], th[i], ts[i], hit)
              : CertifiedKernel::decide_triangle(c, prim(i), vertex(i, 0), vertex(i, 1), vertex(i, 2), u[i], v[i], w[i],
                                                 b[i], za[i], zb[i], zc[i], hit);
      if (won) {
        last = i;
        if constexpr (kAnyHit) return i;
        for (unsigned m = open; m != 0; m &= m - 1)
          if (lower(std::countr_zero(m)) > c.upper) open &= ~(1u << std::countr_zero(m));
      }
    }
    return last;
  }
};

template <>
struct PacketKernel<MollerTrumboreKernel> {
  /// The ray's origin and direction, broadcast at each test.
  struct Ray {
    float o[3], d[3];
    Ray() = default;
    [[gnu::always_inline]] explicit Ray(const MollerTrumboreKernel::Context& c) {
      for (int a = 0; a < 3; ++a) {
        o[a] = c.ray.org[a];
        d[a] = c.ray.dir[a];
      }
    }
  };

  template <bool kAnyHit>
  static int intersect(MollerTrumboreKernel::Context& c, const Ray& r, const TrianglePacket& p, TriangleHit& hit) {
    return intersect_lanes<kAnyHit, kPacketWidth>(c, r, &p, hit);
  }

  /// The kLanes lanes of the kLanes / kPacketWidth consecutive packets from `p`, in order.
  template <bool kAnyHit, int kLanes>
  static int intersect_lanes(MollerTrumboreKernel::Context& c, const Ray& r, const TrianglePacket* p, TriangleHit& hit) {
    using F = simd::Float<kLanes>;
    F o[3], d[3], p0[3], e1[3], e2[3];
    for (int a = 0; a < 3; ++a) {
      o[a] = F::broadcast(r.o[a]);
      d[a] = F::broadcast(r.d[a]);
      p0[a] = load_lanes<kLanes>(p, 0, a);
      e1[a] = load_lanes<kLanes>(p, 1, a) - p0[a];
      e2[a] = load_lanes<kLanes>(p, 2, a) - p0[a];
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
    cross(d, e2, pv);
    const F det = dot(e1, pv);
    const F zero = F::broadcast(0.0f);
    unsigned ok = ~(det == zero) & finite(det) & ((1u << kLanes) - 1);
    if (ok == 0) return -1;
    const F sign = sign_bits(det), abs_det = abs(det);
    for (int a = 0; a < 3; ++a) tv[a] = o[a] - p0[a];
    const F U = dot(tv, pv) ^ sign;
    cross(tv, e1, qv);
    const F V = dot(d, qv) ^ sign;
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
    alignas(32) float ts[kLanes], us[kLanes], vs[kLanes];
    t.store(ts);
    const int best = closest_lane<kAnyHit>(ok, ts);
    u.store(us);
    v.store(vs);
    c.tmax = ts[best];
    hit = {ts[best], us[best], vs[best]};
    return best;
  }
};

/// Offers the `lanes` filled lanes of the kLanes / kPacketWidth consecutive packets from `packets`
/// to PacketKernel<Kernel> (kLanes = 2·kPacketWidth needs its intersect_lanes), counted as a scalar loop
/// would count them (`lanes` tests, at most one hit). On a hit closer than ctx's closest,
/// writes `hit` with the lane's scene primitive id and returns true.
template <class Kernel, bool kAnyHit, int kLanes = kPacketWidth, class Counters>
inline bool intersect_triangle_packets(typename Kernel::Context& ctx, const typename PacketKernel<Kernel>::Ray& packet_ray,
                                       const TrianglePacket* packets, int lanes, Hit& hit, Counters& counters) {
  if constexpr (Counters::enabled)
    for (int i = lanes; i > 0; --i) counters.prim_test();
  TriangleHit th;
  int lane;
  if constexpr (kLanes == kPacketWidth)
    lane = PacketKernel<Kernel>::template intersect<kAnyHit>(ctx, packet_ray, *packets, th);
  else
    lane = PacketKernel<Kernel>::template intersect_lanes<kAnyHit, kLanes>(ctx, packet_ray, packets, th);
  if (lane < 0) return false;
  counters.prim_hit();
  set_scene_hit(hit, th, packets[lane / kPacketWidth].prim[lane % kPacketWidth]);
  return true;
}

/// One packet: intersect_triangle_packets with kLanes = kPacketWidth.
template <class Kernel, bool kAnyHit, class Counters>
inline bool intersect_triangle_packet(typename Kernel::Context& ctx, const typename PacketKernel<Kernel>::Ray& packet_ray,
                                      const TrianglePacket& packet, int lanes, Hit& hit, Counters& counters) {
  return intersect_triangle_packets<Kernel, kAnyHit>(ctx, packet_ray, &packet, lanes, hit, counters);
}

/// Kernels with an 8-lane packet test (PacketKernel::intersect_lanes<kAnyHit, 8>).
template <class Kernel>
inline constexpr bool kPairedPackets = std::is_same_v<Kernel, WatertightKernel> ||
                                       std::is_same_v<Kernel, MollerTrumboreKernel> ||
                                       std::is_same_v<Kernel, CertifiedKernel>;

/// Offers a leaf's `count` packets from `packets` (pack_leaf's order: triangle packets, then
/// sphere packets, tested scalar) to Kernel in order; true when one of them became the closest
/// hit (with kAnyHit: at the first hit). Two consecutive triangle packets go as one 8-lane test
/// where the kernel has one (most leaves of the wide trees' default leaf sizes are 2 or 4 packets).
/// Always inlined into the traversal loops: GCC's unit-growth limit otherwise leaves it out of
/// line once a translation unit instantiates more traversals (it did for the quantized nodes).
template <class Kernel, bool kAnyHit, class Counters>
[[gnu::always_inline]] inline bool intersect_packed_leaf(const Scene& scene, typename Kernel::Context& ctx,
                                  const typename PacketKernel<Kernel>::Ray& packet_ray, const TrianglePacket* packets,
                                  std::uint32_t count, Hit& hit, Counters& counters) {
  bool found = false;
  const TrianglePacket* const end = packets + count;
  for (const TrianglePacket* p = packets; p != end;) {
    if (scene.is_sphere(p->prim[0])) {
      for (int i = 0; i < kPacketWidth && p->prim[i] != kInvalidId; ++i)
        if (intersect_scene_primitive<Kernel>(scene, p->prim[i], ctx, hit, counters)) {
          found = true;
          if constexpr (kAnyHit) return true;
        }
      ++p;
      continue;
    }
    if constexpr (kPairedPackets<Kernel>) {
      if (end - p >= 2 && !scene.is_sphere(p[1].prim[0])) {
        const int lanes = Counters::enabled ? p[0].size() + p[1].size() : 0;
        if (intersect_triangle_packets<Kernel, kAnyHit, 2 * kPacketWidth>(ctx, packet_ray, p, lanes, hit, counters)) {
          found = true;
          if constexpr (kAnyHit) return true;
        }
        p += 2;
        continue;
      }
    }
    if (intersect_triangle_packet<Kernel, kAnyHit>(ctx, packet_ray, *p, Counters::enabled ? p->size() : 0, hit,
                                                   counters)) {
      found = true;
      if constexpr (kAnyHit) return true;
    }
    ++p;
  }
  return found;
}

}  // namespace raylab
