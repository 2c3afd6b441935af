// Ray and hit files: bit-exact round trips and one-line errors naming file and line.
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

#include "geometry/input_error.h"
#include "rays/random.h"
#include "rays/ray_file.h"

namespace raylab {
namespace {

std::string temp_path(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("raylab_test_rays_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

/// The message of the InputError `f` throws, or "" when it throws nothing.
template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

/// A finite float with random bits, weighted toward the awkward ones.
float awkward_float(Rng& rng) {
  switch (rng.below(8)) {
    case 0: return std::bit_cast<float>(static_cast<std::uint32_t>(rng.below(0x800000)));  // denormal or zero
    case 1: return -std::bit_cast<float>(static_cast<std::uint32_t>(1 + rng.below(0x7fffff)));
    case 2: return std::numeric_limits<float>::max() * (rng.below(2) ? 1.0f : -1.0f);
    case 3: return std::numeric_limits<float>::min();
    case 4: return std::numeric_limits<float>::denorm_min();
    default: {
      float f;
      do f = std::bit_cast<float>(static_cast<std::uint32_t>(rng.next_u64()));
      while (!std::isfinite(f));
      return f;
    }
  }
}

TEST(RaysFiles, RayFileRoundTripIsBitExact) {
  Rng rng(99);
  std::vector<Ray> rays;
  for (int i = 0; i < 20000; ++i) {
    Ray r;
    r.org = {awkward_float(rng), awkward_float(rng), awkward_float(rng)};
    do r.dir = {awkward_float(rng), awkward_float(rng), awkward_float(rng)};
    while (r.dir == Vec3f(0.0f));
    const float a = std::abs(awkward_float(rng)), b = std::abs(awkward_float(rng));
    r.tmin = std::min(a, b);
    r.tmax = rng.below(4) == 0 ? std::numeric_limits<float>::infinity() : std::max(a, b);
    rays.push_back(r);
  }
  rays.push_back(Ray{{0, 0, 0}, {0, 0, -1}, 0.0f, 0.0f});
  const std::string path = temp_path("roundtrip.rays");
  write_rays(path, rays);
  const auto back = read_rays(path);
  ASSERT_EQ(back.size(), rays.size());
  EXPECT_EQ(std::memcmp(back.data(), rays.data(), rays.size() * sizeof(Ray)), 0);
}

TEST(RaysFiles, ReadsCommentsBlankLinesAndInf) {
  const std::string path = temp_path("hand.rays");
  write_text(path, "# a comment\n\n  1 2 3\t0 0 1  0 inf\r\n   # indented comment\n0.5 0 0 1 0 0 0.25 2");
  const auto rays = read_rays(path);
  ASSERT_EQ(rays.size(), 2u);
  EXPECT_EQ(rays[0].org, Vec3f(1, 2, 3));
  EXPECT_EQ(rays[0].tmax, std::numeric_limits<float>::infinity());
  EXPECT_EQ(rays[1].tmin, 0.25f);
  EXPECT_EQ(rays[1].tmax, 2.0f);
}

TEST(RaysFiles, MalformedRayLinesNameFileAndLine) {
  const std::string good = "0 0 0 1 0 0 0 inf\n";
  const char* bad[] = {
      "0 0 0 1 0 0 0",            // 7 fields
      "0 0 0 1 0 0 0 inf 1",      // 9 fields
      "nan 0 0 1 0 0 0 inf",      // NaN
      "0 0 0 1 0 0 0 nan",        // NaN tmax
      "0 0 0 1 0 0 2 1",          // tmin > tmax
      "0 0 0 1 0 0 -1 1",         // tmin < 0
      "0 0 0 1 0 0 0 -inf",       // negative infinite tmax
      "inf 0 0 1 0 0 0 1",        // infinite origin
      "0 0 0 1 0 0 inf inf",      // infinite tmin
      "0 0 0 1x 0 0 0 1",         // garbage after a number
      "a b c d e f g h",          // garbage
      "0 0 0 0 0 0 0 1",          // zero direction
      "0 0 0 -0 0 0 0 1",         // zero direction (negative zero)
      "0 0 0 1e39 0 0 0 1",       // outside the float range
      "0 0 0 1 0 0 0 +1",         // a sign from_chars does not take
  };
  int k = 0;
  for (const char* line : bad) {
    const std::string path = temp_path("bad" + std::to_string(k++) + ".rays");
    write_text(path, "# header\n" + good + line + "\n" + good);
    const std::string msg = error_of([&] { read_rays(path); });
    EXPECT_EQ(msg.rfind(path + ":3: ", 0), 0u) << line << " -> '" << msg << "'";
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}

TEST(RaysFiles, EmptyAndMissingFiles) {
  const std::string path = temp_path("empty.rays");
  write_text(path, "# only a comment\n\n");
  EXPECT_EQ(error_of([&] { read_rays(path); }), path + ": no rays");
  write_text(path, "");
  EXPECT_EQ(error_of([&] { read_rays(path); }), path + ": no rays");
  EXPECT_NE(error_of([&] { read_rays(temp_path("missing.rays")); }), "");
  EXPECT_NE(error_of([&] { write_rays("/nonexistent-dir/x.rays", {}); }), "");
  write_text(path, std::string(100000, '1') + "\n");
  EXPECT_EQ(error_of([&] { read_rays(path); }).rfind(path + ":1: ", 0), 0u);
}

TEST(RaysFiles, HitCsvRoundTrip) {
  Rng rng(5);
  std::vector<Hit> hits;
  for (unsigned i = 0; i < 5000; ++i) {
    if (rng.below(3) == 0) {
      hits.push_back(Hit{});
      continue;
    }
    hits.push_back(Hit{std::abs(awkward_float(rng)), awkward_float(rng), awkward_float(rng),
                       static_cast<unsigned>(rng.below(kInvalidId)), kInvalidId});
  }
  const std::string path = temp_path("hits.csv");
  write_hits_csv(path, hits);
  {
    std::ifstream in(path);
    std::string header, first;
    std::getline(in, header);
    EXPECT_EQ(header, "ray,prim,t,u,v");
  }
  auto back = read_hits_csv(path);
  ASSERT_EQ(back.size(), hits.size());
  EXPECT_EQ(std::memcmp(back.data(), hits.data(), hits.size() * sizeof(Hit)), 0);

  hits[1].instance = 7;
  hits[1].prim = 3;
  write_hits_csv(path, hits);
  back = read_hits_csv(path);
  ASSERT_EQ(back.size(), hits.size());
  EXPECT_EQ(std::memcmp(back.data(), hits.data(), hits.size() * sizeof(Hit)), 0);
}

TEST(RaysFiles, MalformedHitRowsNameFileAndLine) {
  const char* bad[] = {"1,0,1,0,0",  "0,0,1,0",   "0,x,1,0,0", "0,-1,1,0,0",
                       "0,0,nan,0,0", "0,0,inf,0,0", "0,4294967295,1,0,0", "0,0,1,0,0,"};
  int k = 0;
  for (const char* row : bad) {
    const std::string path = temp_path("badhits" + std::to_string(k++) + ".csv");
    write_text(path, std::string("ray,prim,t,u,v\n") + row + "\n");
    const std::string msg = error_of([&] { read_hits_csv(path); });
    EXPECT_EQ(msg.rfind(path + ":2: ", 0), 0u) << row << " -> '" << msg << "'";
  }
  const std::string path = temp_path("badheader.csv");
  write_text(path, "ray,prim,t\n0,0,1\n");
  EXPECT_EQ(error_of([&] { read_hits_csv(path); }).rfind(path + ":1: ", 0), 0u);
}

}  // namespace
}  // namespace raylab
