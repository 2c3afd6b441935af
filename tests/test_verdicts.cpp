// Verdicts decided by intervals (experiments/experiment_common.h) and the full specs key numbers
// name (canonical_spec, accel_factory.h).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "../experiments/experiment_common.h"
#include "accel/common/accel_factory.h"
#include "geometry/input_error.h"

using namespace raylab;
using namespace raylab::experiments;

namespace {

KeyNumber interval(double lo, double hi) {
  KeyNumber k;
  k.value = (lo + hi) / 2;
  k.lo = lo;
  k.hi = hi;
  return k;
}

}  // namespace

TEST(Verdicts, BelowAndAboveDecideOnlyWhenTheIntervalClearsTheThreshold) {
  const Threshold below{"α below 0.25", "below", 0.25};
  EXPECT_EQ(decide_verdict(interval(0.13, 0.17), below), kConfirmed);
  EXPECT_EQ(decide_verdict(interval(0.33, 0.36), below), kRefuted);
  EXPECT_EQ(decide_verdict(interval(0.20, 0.30), below), kInconclusive);
  const Threshold above{"ratio above 1", "above", 1.0};
  EXPECT_EQ(decide_verdict(interval(10.0, 18.6), above), kConfirmed);
  EXPECT_EQ(decide_verdict(interval(0.5, 0.9), above), kRefuted);
  EXPECT_EQ(decide_verdict(interval(0.9, 1.1), above), kInconclusive);
}

TEST(Verdicts, WithinNeedsTheWholeIntervalInsideTheTolerance) {
  const Threshold within{"c within 1 ± 0.02", "within", 1.0, 0.02};
  EXPECT_EQ(decide_verdict(interval(0.9876, 0.9998), within), kConfirmed);
  EXPECT_EQ(decide_verdict(interval(0.56, 0.77), within), kRefuted);
  EXPECT_EQ(decide_verdict(interval(1.03, 1.05), within), kRefuted);
  EXPECT_EQ(decide_verdict(interval(0.97, 0.99), within), kInconclusive);
}

TEST(Verdicts, UndefinedIntervalIsInconclusive) {
  KeyNumber k;
  k.value = 0.1;
  EXPECT_EQ(decide_verdict(k, Threshold{"", "below", 0.25}), kInconclusive);
  EXPECT_THROW(decide_verdict(interval(0, 1), Threshold{"", "sideways", 0.0}), std::logic_error);
}

TEST(Verdicts, CombinedVerdicts) {
  EXPECT_EQ(decide_all({kConfirmed, kConfirmed}), kConfirmed);
  EXPECT_EQ(decide_all({kConfirmed, kInconclusive}), kInconclusive);
  EXPECT_EQ(decide_all({kInconclusive, kRefuted}), kRefuted);
  EXPECT_EQ(decide_all({}), kInconclusive);
  EXPECT_EQ(decide_conditional({kConfirmed, kRefuted}), kConditional);
  EXPECT_EQ(decide_conditional({kConfirmed, kConfirmed}), kConfirmed);
  EXPECT_EQ(decide_conditional({kRefuted, kInconclusive}), kInconclusive);
}

TEST(Verdicts, GatedVerdictNeedsItsFirstCase) {
  EXPECT_EQ(decide_gated({kConfirmed, kConfirmed}), kConfirmed);
  EXPECT_EQ(decide_gated({kConfirmed, kRefuted}), kConditional);
  EXPECT_EQ(decide_gated({kRefuted, kConfirmed}), kRefuted);
  EXPECT_EQ(decide_gated({kRefuted, kInconclusive}), kInconclusive);
  EXPECT_EQ(decide_gated({}), kInconclusive);
}

TEST(Verdicts, PartsAreWrittenBesideTheirVerdictAndMustDecideIt) {
  const std::string dir = ::testing::TempDir() + "verdict_parts";
  std::filesystem::create_directories(dir);
  const Threshold below{"t below 1.1", "below", 1.1};
  KeyNumber grass = interval(1.00, 1.01), sphereflake = interval(1.05, 1.06);
  grass.name = "t(3)/t(d*) on grass";
  sphereflake.name = "t(3)/t(d*) on sphereflake";
  Verdict v{"6a", "grid resolution", kConfirmed, "holds", "claim-6", grass, below};
  v.parts = {{grass, below}, {sphereflake, below}};
  v.parts_rule = "conditional";
  EXPECT_EQ(decide_parts(v), kConfirmed);
  write_verdicts(dir, "grids", {v});
  std::ifstream parts(dir + "/grids.verdict_parts.csv");
  std::string header, first, second, none;
  std::getline(parts, header);
  std::getline(parts, first);
  std::getline(parts, second);
  EXPECT_EQ(header.rfind("claim,rule,part,name,", 0), 0u) << header;
  EXPECT_EQ(first.rfind("6a,conditional,0,t(3)/t(d*) on grass,", 0), 0u) << first;
  EXPECT_EQ(second.rfind("6a,conditional,1,t(3)/t(d*) on sphereflake,", 0), 0u) << second;
  EXPECT_FALSE(std::getline(parts, none));
  // A part failing its threshold makes the rule's verdict differ from the row's: refused.
  v.parts[1].first = interval(1.2, 1.3);
  EXPECT_EQ(decide_parts(v), kConditional);
  EXPECT_THROW(write_verdicts(dir, "grids", {v}), std::logic_error);
  // A later run without parts leaves no stale parts file.
  v.parts.clear();
  write_verdicts(dir, "grids", {v});
  EXPECT_FALSE(std::filesystem::exists(dir + "/grids.verdict_parts.csv"));
}

TEST(Verdicts, FittedKeyUsesStudentsT) {
  // 5 points, 1 parameter: t(0.975, 4) = 2.776.
  const KeyNumber k = fitted_key("c", 1.0, 0.01, 5, 1, "bvh");
  EXPECT_NEAR(k.hi - k.value, 0.02776, 1e-5);
  EXPECT_NEAR(k.value - k.lo, 0.02776, 1e-5);
  EXPECT_EQ(k.replicates, 5);
  // Many points: close to 1.96.
  EXPECT_NEAR(fitted_key("c", 0.0, 1.0, 100002, 2, "").hi, 1.96, 1e-3);
  // No degrees of freedom, or no standard error: no interval.
  EXPECT_TRUE(std::isnan(fitted_key("c", 1.0, 0.01, 2, 2, "").lo));
  EXPECT_TRUE(std::isnan(fitted_key("c", 1.0, std::nan(""), 9, 2, "").hi));
}

TEST(CanonicalSpec, ExpandsEveryDefaultInDocumentedOrder) {
  const std::string k = canonical_spec("kdtree");
  EXPECT_EQ(k.rfind("kdtree:builder=sah,sweep=events,clip=exact,", 0), 0u) << k;
  EXPECT_NE(k.find("mailbox=off"), std::string::npos) << k;
  // A given value replaces its default in place; the order does not depend on how it was given.
  EXPECT_EQ(canonical_spec("kdtree:mailbox=on,sweep=sort"),
            canonical_spec("kdtree:sweep=sort,mailbox=on"));
  EXPECT_NE(canonical_spec("kdtree:sweep=sort").find("sweep=sort"), std::string::npos);
  // The default spelled out equals the default left out.
  EXPECT_EQ(canonical_spec("kdtree:builder=sah"), k);
  // Defaults that depend on other parameters are written as their documentation, in parentheses.
  EXPECT_NE(canonical_spec("bvh").find("leaf_size=("), std::string::npos) << canonical_spec("bvh");
}

TEST(CanonicalSpec, RejectsUnknownNamesAndKeys) {
  EXPECT_THROW(canonical_spec("no-such-accel"), InputError);
  EXPECT_THROW(canonical_spec("kdtree:no_such_key=1"), InputError);
}
