// The heatmap's colour scale (tools/heatmap_image.h): it spans the data's range, so that an image
// whose costs lie close together is not painted in one colour.
#include <gtest/gtest.h>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

#include "../tools/heatmap_image.h"

namespace raylab {
namespace {

using Rgb = std::array<int, 3>;

/// The colour of pixel (x, y) of a PNG file.
Rgb pixel(const std::string& path, int x, int y) {
  int w = 0, h = 0, n = 0;
  unsigned char* data = stbi_load(path.c_str(), &w, &h, &n, 3);
  EXPECT_NE(data, nullptr) << path;
  if (!data) return {-1, -1, -1};
  const unsigned char* p = data + (static_cast<std::size_t>(y) * w + x) * 3;
  const Rgb c{p[0], p[1], p[2]};
  stbi_image_free(data);
  return c;
}

TEST(HeatmapImage, PositionSpansTheGivenRangeOnBothScales) {
  for (const HeatmapScale s : {HeatmapScale::linear, HeatmapScale::log}) {
    EXPECT_DOUBLE_EQ(heatmap_position(19000, 19000, 20047, s), 0.0);
    EXPECT_DOUBLE_EQ(heatmap_position(20047, 19000, 20047, s), 1.0);
    const double mid = heatmap_position(19500, 19000, 20047, s);
    EXPECT_GT(mid, 0.4);
    EXPECT_LT(mid, 0.55);
    EXPECT_DOUBLE_EQ(heatmap_position(5, 19000, 20047, s), 0.0);  // below the scale: saturates
    EXPECT_DOUBLE_EQ(heatmap_position(7, 7, 7, s), 0.5);          // a constant image
  }
  // On the log scale a decade is a decade wherever it lies.
  EXPECT_NEAR(heatmap_position(99, 9, 999, HeatmapScale::log), 0.5, 0.01);
}

TEST(HeatmapImage, CostsCloseTogetherStillSpanTheColourRamp) {
  // Costs of 19000 .. 20047, as every ray through a grid cell of 20000 triangles: with the scale
  // starting at 0 they would all be drawn near the top colour.
  const int width = 4, height = 2;
  const std::vector<float> costs = {19000, 19300, 19600, 20047, 19100, 19400, 19700, 20000};
  const std::string path =
      (std::filesystem::temp_directory_path() / ("raylab_heatmap_test_" + std::to_string(::getpid()) + ".png")).string();
  write_heatmap_png(path, costs, width, height, "test", HeatmapScale::log);
  const Rgb least = pixel(path, 0, 0), largest = pixel(path, 3, 0);
  EXPECT_EQ(least, (Rgb{68, 1, 84}));      // the ramp's bottom: dark blue
  EXPECT_EQ(largest, (Rgb{253, 231, 37}));  // its top: yellow
  // A fixed scale from 0 (several images sharing one) puts them all near the top, as asked.
  write_heatmap_png(path, costs, width, height, "test", HeatmapScale::log, 20047, 0);
  const Rgb shared = pixel(path, 0, 0);
  EXPECT_GT(shared[0], 200);
  // A constant image is drawn (one colour) without failing.
  write_heatmap_png(path, std::vector<float>(8, 5.0f), width, height, "constant", HeatmapScale::log);
  EXPECT_EQ(pixel(path, 0, 0), pixel(path, 3, 1));
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace raylab
