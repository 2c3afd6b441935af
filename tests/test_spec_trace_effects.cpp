// Spec effects on trace time (spec_trace_effects.h): the two-way fit recovers known effects from an
// unbalanced design (no spec on every scene), the spread measures the noise, and model.json
// round-trips them and rejects malformed entries with one error naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "cost/spec_trace_effects.h"
#include "geometry/input_error.h"

namespace raylab {
namespace {

RunRecord row(const std::string& accel, const std::string& scene, const std::string& rays, double ns) {
  RunRecord r;
  r.accel = accel;
  r.scene = scene;
  r.rays = rays;
  r.ray_kind = rays.substr(0, rays.find(':'));
  r.ns_per_ray_min = ns;
  return r;
}

/// Specs A, B and C with effects 0, ln 1.5 and ln 0.8 on camera rays (ln 2, ln 0.5 larger on
/// bounce rays for B and C), on eight scenes whose own effects spread 300-fold; A is on every
/// scene, B on the even ones, C on scenes 3 to 7: the differences of B and C reach each other only
/// through A. Times are exp(a + b) times lognormal noise of `sigma`.
std::vector<RunRecord> unbalanced_rows(double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<RunRecord> rows;
  for (int s = 0; s < 8; ++s) {
    const std::string scene = "scene" + std::to_string(s);
    const double b = 3.0 + 0.8 * s;
    for (const char* rays : {"primary:64", "diffuse:64"}) {
      const bool bounce = rays[0] == 'd';
      auto add = [&](const char* accel, double a) { rows.push_back(row(accel, scene, rays, std::exp(a + b + noise(rng)))); };
      add("A", bounce ? 0.3 : 0.0);
      if (s % 2 == 0) add("B", std::log(1.5) + (bounce ? 0.3 + std::log(2.0) : 0.0));
      if (s >= 3) add("C", std::log(0.8) + (bounce ? 0.3 + std::log(0.5) : 0.0));
    }
  }
  return rows;
}

TEST(SpecTraceEffects, RecoverKnownEffectsFromAnUnbalancedDesign) {
  const SpecTraceEffects e = fit_spec_trace_effects(unbalanced_rows(0.0, 1));
  ASSERT_EQ(e.by_spec.size(), 3u);
  const auto effect = [&](const char* spec, const char* cls) { return e.by_spec.at(spec).at(cls).effect; };
  EXPECT_NEAR(effect("B", "camera") - effect("A", "camera"), std::log(1.5), 1e-6);
  EXPECT_NEAR(effect("C", "camera") - effect("A", "camera"), std::log(0.8), 1e-6);
  EXPECT_NEAR(effect("B", "camera") - effect("C", "camera"), std::log(1.5 / 0.8), 1e-6);
  EXPECT_NEAR(effect("B", "bounce") - effect("A", "bounce"), std::log(1.5 * 2.0), 1e-6);
  EXPECT_NEAR(effect("C", "bounce") - effect("A", "bounce"), std::log(0.8 * 0.5), 1e-6);
  EXPECT_EQ(e.by_spec.at("A").at("camera").scenes, 8u);
  EXPECT_EQ(e.by_spec.at("B").at("bounce").scenes, 4u);
  EXPECT_EQ(e.by_spec.at("C").at("camera").scenes, 5u);
  for (const auto& [spec, by_class] : e.by_spec)
    for (const auto& [cls, x] : by_class) EXPECT_LT(x.log_q90, 1e-6) << spec << " " << cls << ": no noise, no spread";
}

TEST(SpecTraceEffects, TheSpreadMeasuresTheNoiseAndReplicatesCountOnce) {
  std::vector<RunRecord> rows = unbalanced_rows(0.1, 2);
  const SpecTraceEffects noisy = fit_spec_trace_effects(rows);
  for (const auto& [spec, by_class] : noisy.by_spec)
    for (const auto& [cls, x] : by_class) {
      EXPECT_GT(x.log_q90, 0.01) << spec << " " << cls;
      EXPECT_LT(x.log_q90, 0.4) << spec << " " << cls;  // about 1.645 σ, less the fit's own share
    }
  // A slower replicate of every case changes nothing: each (spec, scene, rays) keeps its fastest time.
  const std::size_t n = rows.size();
  for (std::size_t i = 0; i < n; ++i) {
    RunRecord slower = rows[i];
    slower.ns_per_ray_min *= 3.0;
    rows.push_back(slower);
  }
  rows.push_back(row("A", "scene0", "primary:64", 0.0));  // no time: left out
  const SpecTraceEffects again = fit_spec_trace_effects(rows);
  for (const auto& [spec, by_class] : noisy.by_spec)
    for (const auto& [cls, x] : by_class) {
      EXPECT_DOUBLE_EQ(again.by_spec.at(spec).at(cls).effect, x.effect) << spec << " " << cls;
      EXPECT_EQ(again.by_spec.at(spec).at(cls).scenes, x.scenes);
    }
}

TEST(SpecTraceEffects, ModelJsonRoundTripsAndRejectsMalformedEntries) {
  const SpecTraceEffects e = fit_spec_trace_effects(unbalanced_rows(0.05, 3));
  const nlohmann::ordered_json j = spec_trace_effects_json(e);
  const SpecTraceEffects back = read_spec_trace_effects(j, "model.scene_trace_effects");
  for (const auto& [spec, by_class] : e.by_spec)
    for (const auto& [cls, x] : by_class) {
      EXPECT_DOUBLE_EQ(back.by_spec.at(spec).at(cls).effect, x.effect);
      EXPECT_DOUBLE_EQ(back.by_spec.at(spec).at(cls).log_q90, x.log_q90);
      EXPECT_EQ(back.by_spec.at(spec).at(cls).scenes, x.scenes);
    }
  auto rejects = [&](nlohmann::ordered_json bad, const std::string& named) {
    try {
      read_spec_trace_effects(bad, "model.scene_trace_effects");
      ADD_FAILURE() << "accepted " << bad.dump();
    } catch (const InputError& err) {
      EXPECT_NE(std::string(err.what()).find(named), std::string::npos) << err.what();
    }
  };
  nlohmann::ordered_json bad = j;
  bad["B"]["camera"]["log_q90"] = -0.1;
  rejects(bad, "model.scene_trace_effects.B.camera.log_q90");
  bad = j;
  bad["C"]["bounce"].erase("effect");
  rejects(bad, "model.scene_trace_effects.C.bounce: missing key 'effect'");
  bad = j;
  bad["A"]["camera"]["scenes"] = 0;
  rejects(bad, "model.scene_trace_effects.A.camera.scenes");
  rejects(nlohmann::ordered_json::array(), "model.scene_trace_effects: expected a JSON object");
}

}  // namespace
}  // namespace raylab
