#include "tools/heatmap_image.h"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#include <stb/stb_easy_font.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

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

void write_heatmap_png(const std::string& path, const std::vector<float>& costs, int width, int height,
                       const std::string& title) {
  const int bar = 90, footer = 28;
  Image img(width + bar, height + footer, 255);
  const double max_cost = std::max(1.0f, *std::max_element(costs.begin(), costs.end()));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) img.set(x, y, ramp(costs[static_cast<std::size_t>(y) * width + x] / max_cost));
  const int bx = width + 12, bw = 18;
  for (int y = 0; y < height; ++y)
    for (int x = bx; x < bx + bw; ++x) img.set(x, y, ramp(1.0 - static_cast<double>(y) / std::max(1, height - 1)));
  const Rgb black{0, 0, 0};
  img.text(bx + bw + 4, 2, number(max_cost), 1, black);
  img.text(bx + bw + 4, height / 2 - 4, number(max_cost / 2), 1, black);
  img.text(bx + bw + 4, height - 10, "0", 1, black);
  img.text(4, height + 8, title, 1, black);
  img.save(path);
}

}  // namespace raylab
