#include "tools/heatmap_image.h"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#include <stb/stb_easy_font.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "accel/common/tracer.h"
#include "geometry/float_mode.h"
#include "geometry/input_error.h"
#include "rays/surface_rays.h"

namespace raylab {
namespace {

using Rgb = std::array<unsigned char, 3>;

struct Image {
  int width, height;
  std::vector<unsigned char> pixels;
  Image(int w, int h, unsigned char fill) : width(w), height(h), pixels(static_cast<std::size_t>(w) * h * 3, fill) {}
  void set(int x, int y, const Rgb& c) {
    if (x < 0 || y < 0 || x >= width || y >= height) return;
    auto* p = &pixels[(static_cast<std::size_t>(y) * width + x) * 3];
    p[0] = c[0]; p[1] = c[1]; p[2] = c[2];
  }
  /// Text through stb_easy_font's quads, scaled by `scale`.
  void text(int x, int y, const std::string& s, int scale, const Rgb& c) {
    static char buffer[200000];
    const int quads = stb_easy_font_print(0, 0, const_cast<char*>(s.c_str()), nullptr, buffer, sizeof(buffer));
    const float* v = reinterpret_cast<const float*>(buffer);
    for (int q = 0; q < quads; ++q) {
      const float* quad = v + q * 16;  // 4 vertices of (x, y, z, color)
      const int x0 = static_cast<int>(quad[0]), y0 = static_cast<int>(quad[1]);
      const int x1 = static_cast<int>(quad[8]), y1 = static_cast<int>(quad[9]);
      for (int yy = y0 * scale; yy < y1 * scale; ++yy)
        for (int xx = x0 * scale; xx < x1 * scale; ++xx) set(x + xx, y + yy, c);
    }
  }
  void save(const std::string& path) const {
    if (!stbi_write_png(path.c_str(), width, height, 3, pixels.data(), width * 3))
      throw InputError("cannot write " + path);
  }
};

/// A viridis-like ramp: dark blue, teal, green, yellow.
Rgb ramp(double x) {
  static const double stops[5][3] = {{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {253, 231, 37}};
  x = std::clamp(x, 0.0, 1.0) * 4.0;
  const int i = std::min(3, static_cast<int>(x));
  const double f = x - i;
  Rgb c;
  for (int k = 0; k < 3; ++k) c[k] = static_cast<unsigned char>(stops[i][k] + f * (stops[i + 1][k] - stops[i][k]));
  return c;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), v >= 1000 ? "%.0f" : "%.3g", v);
  return buf;
}

}  // namespace

double shading_cosine(const Scene& scene, const Hit& hit, const Ray& ray, const Vec3d& light) {
  const SurfacePoint sp = surface_at(scene, ray, hit);
  return 0.15 + 0.85 * std::abs(dot(Vec3d(sp.n), light));
}

void write_shaded_png(const std::string& path, const std::vector<float>& values, int width, int height) {
  Image img(width, height, 0);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float v = values[static_cast<std::size_t>(y) * width + x];
      if (v < 0) img.set(x, y, {40, 44, 52});
      else {
        const auto g = static_cast<unsigned char>(std::clamp(v, 0.0f, 1.0f) * 255.0f);
        img.set(x, y, {g, static_cast<unsigned char>(g * 0.95), static_cast<unsigned char>(g * 0.85)});
      }
    }
  img.save(path);
}

double heatmap_position(double c, double lo, double hi, HeatmapScale scale) {
  if (!(hi > lo)) return 0.5;
  const auto f = [&](double v) { return scale == HeatmapScale::log ? std::log1p(std::max(0.0, v)) : v; };
  return std::clamp((f(c) - f(lo)) / (f(hi) - f(lo)), 0.0, 1.0);
}

void write_heatmap_png(const std::string& path, const std::vector<float>& costs, int width, int height,
                       const std::string& title, HeatmapScale scale, double max_cost, double min_cost) {
  const int bar = 90, footer = 28;
  Image img(width + bar, height + footer, 255);
  const auto [least, largest] = std::minmax_element(costs.begin(), costs.end());
  const double hi = max_cost > 0 ? max_cost : costs.empty() ? 1.0 : static_cast<double>(*largest);
  const double lo = min_cost >= 0 ? min_cost : costs.empty() ? 0.0 : std::min(hi, static_cast<double>(*least));
  const bool log_scale = scale == HeatmapScale::log;
  auto position = [&](double c) { return heatmap_position(c, lo, hi, scale); };
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) img.set(x, y, ramp(position(costs[static_cast<std::size_t>(y) * width + x])));
  const int bx = width + 12, bw = 18;
  for (int y = 0; y < height; ++y)
    for (int x = bx; x < bx + bw; ++x) img.set(x, y, ramp(1.0 - static_cast<double>(y) / std::max(1, height - 1)));
  const Rgb black{0, 0, 0};
  auto label = [&](double c) {
    const int y = static_cast<int>(std::lround((1.0 - position(c)) * (height - 1)));
    img.text(bx + bw + 4, std::clamp(y - 4, 2, height - 10), number(c), 1, black);
  };
  label(hi);
  if (hi > lo) {
    label(lo);
    int between = 0;
    if (log_scale)
      for (double c = std::pow(10.0, std::floor(std::log10(std::max(1.0, lo))) + 1); c < hi; c *= 10)
        if (position(c) > 0.08 && position(c) < 0.92) label(c), ++between;
    if (between == 0) label(log_scale ? std::expm1(0.5 * (std::log1p(lo) + std::log1p(hi))) : 0.5 * (lo + hi));
  }
  img.text(4, height + 8, title + (log_scale ? " (log colour scale)" : ""), 1, black);
  img.save(path);
}

std::vector<float> traversal_cost_per_ray(const Aggregate& accel, const std::vector<Ray>& rays, int threads) {
  if (!accel.reports_counters()) throw InputError("heatmap: accelerator '" + accel.name() + "' reports no traversal counters");
  std::vector<float> values(rays.size());
  tbb::task_arena arena(resolve_thread_count(threads));
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rays.size(), 256), [&](const auto& range) {
      const FloatModeScope ftz(true);
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        RayCounters c;
        Ray r = rays[i];
        Hit h;
        accel.intersect(r, h, c);
        values[i] = static_cast<float>(c.nodes + c.leaves + c.prim_tests);
      }
    });
  });
  return values;
}

}  // namespace raylab
