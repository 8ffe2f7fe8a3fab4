// Bodies with long limbs: seeds at the limb tips put every limb at a patch corner,
// where a quinary split can only slice it lengthwise. The stop rules keep such a layout small and
// leave no large leaf over tau: a small over-tau patch is not split (min_split_area), a large one
// still over tau after the repair is split even without progress (force_split_area).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"

namespace {

// A T-posed figure: an ellipsoidal body with two arms and two legs, each a cylinder of radius
// `rho` with a round cap at distance `tip` from the centre, as a radial graph over the unit sphere
// (star-shaped, so a valid closed surface). The icosphere's directions are pulled towards each
// limb axis (theta -> t1 (theta / t1)^2.5 within t1 = 0.6 rad) so that the thin limbs get enough
// vertices. seeds: the vertices nearest the four limb tips, in loop order (left arm, right arm,
// right leg, left leg).
struct Body {
  qs::TriMesh mesh;
  std::array<int, 4> seeds{};
};

Body long_limbed_body(double tip, double rho) {
  Body b;
  b.mesh = qs::shapes::icosphere(5);
  std::array<qs::Vec3, 4> limbs = {qs::Vec3(-1, 0.12, 0), qs::Vec3(1, 0.12, 0), qs::Vec3(0.3, -1, 0),
                                   qs::Vec3(-0.3, -1, 0)};
  for (auto& a : limbs) a.normalize();
  const double t1 = 0.6;
  std::vector<qs::Vec3> dirs = b.mesh.positions;
  for (const auto& a : limbs)
    for (auto& d : dirs) {
      const double c = std::clamp(d.dot(a), -1.0, 1.0), th = std::acos(c);
      if (th >= t1) continue;
      qs::Vec3 perp = d - c * a;
      if (perp.norm() < 1e-300) continue;
      perp.normalize();
      const double tn = t1 * std::pow(th / t1, 2.5);
      d = std::cos(tn) * a + std::sin(tn) * perp;
    }
  for (size_t v = 0; v < dirs.size(); ++v) {
    const qs::Vec3& d = dirs[v];
    double r = 1 / std::sqrt(std::pow(d.x() / 0.7, 2) + std::pow(d.y() / 1.1, 2) + std::pow(d.z() / 0.45, 2));
    for (const auto& a : limbs) {
      const double c = std::clamp(d.dot(a), -1.0, 1.0), th = std::acos(c);
      if (c <= 0) continue;
      const double c0 = tip - rho;  // the cap's centre on the axis
      double limb;
      if (th < std::asin(std::min(1.0, rho / c0))) {
        const double p = c0 * c, disc = p * p - (c0 * c0 - rho * rho);
        limb = p + std::sqrt(std::max(disc, 0.0));
      } else {
        limb = std::min(rho / std::max(std::sin(th), 1e-9), c0 * c);
      }
      const double k = 8;  // smooth union with the body
      r = std::log(std::exp(k * r) + std::exp(k * limb)) / k;
    }
    b.mesh.positions[v] = r * d;
  }
  for (int i = 0; i < 4; ++i) {
    int best = 0;
    for (size_t v = 0; v < dirs.size(); ++v)
      if (dirs[v].dot(limbs[i]) > dirs[best].dot(limbs[i])) best = static_cast<int>(v);
    b.seeds[i] = best;
  }
  return b;
}

// Per leaf: its share of the surface area (chart faces by patch).
std::vector<double> leaf_area_shares(const qs::dissect::Dissection& d) {
  const auto& m = d.chart.mesh;
  std::vector<double> a(d.chart.patches.size(), 0.0);
  double total = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    const auto& t = m.faces[f];
    const double fa =
        0.5 * (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]).norm();
    a[d.chart.face_patch[f]] += fa;
    total += fa;
  }
  for (double& x : a) x /= total;
  return a;
}

struct Layout {
  size_t patches = 0;
  double largest_over_tau = 0;  // area share of the largest leaf left over tau
  int small_area_leaves = 0;
};

Layout layout_of(const qs::dissect::Dissection& d, const qs::dissect::DissectOptions& o) {
  Layout l;
  l.patches = d.chart.patches.size();
  const auto share = leaf_area_shares(d);
  for (size_t i = 0; i < share.size(); ++i) {
    const auto& p = d.chart.patches[i];
    EXPECT_EQ(p.flipped_faces + p.zero_area_faces, 0) << p.name;
    if (p.stretch > o.tau) l.largest_over_tau = std::max(l.largest_over_tau, share[i]);
    if (p.stop == qs::dissect::StopReason::SmallArea) {
      ++l.small_area_leaves;
      // The rule's own invariant: only a patch smaller than min_split_area stops for its size.
      EXPECT_LT(share[i], o.min_split_area * (1 + 1e-9)) << p.name;
    }
  }
  return l;
}

const Body& thin_body() {
  static const Body b = [] {
    Body x = long_limbed_body(3.5, 0.1);
    x.mesh = qs::mesh::validate(x.mesh).mesh;  // the validated mesh keeps vertex ids
    return x;
  }();
  return b;
}

TEST(LongLimbs, BodyWithSeedsAtLimbTipsHasFewPatchesAndNoLargeLeafOverTau) {
  const Body& b = thin_body();
  qs::dissect::DissectOptions o;  // the defaults
  const auto d = qs::dissect::dissect(b.mesh, b.seeds, o);
  const Layout l = layout_of(d, o);
  EXPECT_TRUE(d.base.closed_conforming);
  EXPECT_EQ(d.base.euler_characteristic, 2);
  EXPECT_LE(l.patches, 200u);
  EXPECT_LT(l.largest_over_tau, 0.05) << "a leaf over tau holds " << 100 * l.largest_over_tau << "% of the surface";
}

TEST(LongLimbs, ForceSplitAreaBreaksUpLargeLeavesOverTau) {
  // Without the rule, the no-progress stop leaves leaves over tau that hold 5-15% of this body;
  // with it, no over-tau leaf holds force_split_area or more unless a depth or size limit stopped it.
  const Body& b = thin_body();
  qs::dissect::DissectOptions off;
  off.force_split_area = 0;
  const Layout before = layout_of(qs::dissect::dissect(b.mesh, b.seeds, off), off);
  qs::dissect::DissectOptions on;
  const auto d = qs::dissect::dissect(b.mesh, b.seeds, on);
  const Layout after = layout_of(d, on);
  EXPECT_GE(before.largest_over_tau, on.force_split_area) << "the test should exercise the rule";
  EXPECT_LT(after.largest_over_tau, before.largest_over_tau);
  const auto share = leaf_area_shares(d);
  for (size_t i = 0; i < share.size(); ++i) {
    const auto& p = d.chart.patches[i];
    if (p.stretch > on.tau && share[i] >= on.force_split_area) {
      EXPECT_TRUE(p.stop == qs::dissect::StopReason::MaxDepth || p.stop == qs::dissect::StopReason::TooFewFaces)
          << p.name << " holds " << share[i] << " of the surface, stretch " << p.stretch << ", stopped "
          << qs::dissect::stop_reason_name(p.stop);
    }
  }
}

TEST(LongLimbs, MinSplitAreaKeepsSmallPatchesOverTauWhole) {
  // A smaller threshold allows more splits; off (0) allows the most. Every small_area leaf is
  // smaller than the threshold and bijective (checked in layout_of).
  const Body& b = thin_body();
  qs::dissect::DissectOptions off;
  off.min_split_area = 0;
  qs::dissect::DissectOptions on;
  const Layout l_off = layout_of(qs::dissect::dissect(b.mesh, b.seeds, off), off);
  const Layout l_on = layout_of(qs::dissect::dissect(b.mesh, b.seeds, on), on);
  EXPECT_EQ(l_off.small_area_leaves, 0);
  EXPECT_GT(l_on.small_area_leaves, 0) << "the test should exercise the rule";
  EXPECT_LT(l_on.patches, l_off.patches);
}

TEST(LongLimbs, AreaExtraDepthSplitsLargeLeavesOverTauPastMaxDepth) {
  // Seeds on a belt around the body: every limb is a protrusion of a seed patch that
  // each split hands to its centre child. With area_extra_depth 0, leaves over tau holding
  // force_split_area or more stop at max_depth; with it (default 4), such a leaf stops for depth
  // only at max_depth + area_extra_depth, and the largest over-tau leaf is smaller.
  const Body& b = thin_body();
  // Seeds on a belt around the waist, between the arms and the legs (the surface is a radial
  // graph: the vertex whose direction is nearest each belt direction).
  std::array<int, 4> belt{};
  const std::array<qs::Vec3, 4> around = {qs::Vec3(1, -0.35, 0), qs::Vec3(0, -0.35, 1), qs::Vec3(-1, -0.35, 0),
                                          qs::Vec3(0, -0.35, -1)};
  for (int i = 0; i < 4; ++i) {
    double best = -2;
    for (int v = 0; v < b.mesh.num_vertices(); ++v) {
      const double c = b.mesh.positions[v].normalized().dot(around[i].normalized());
      if (c > best) best = c, belt[i] = v;
    }
  }
  // A low max_depth (2) so that this small body reaches it with large leaves over tau.
  qs::dissect::DissectOptions off;
  off.max_depth = 2;
  off.area_extra_depth = 0;
  const auto d_off = qs::dissect::dissect(b.mesh, belt, off);
  const Layout before = layout_of(d_off, off);
  qs::dissect::DissectOptions on;
  on.max_depth = 2;
  const auto d = qs::dissect::dissect(b.mesh, belt, on);
  const Layout after = layout_of(d, on);
  auto large_at_depth = [](const qs::dissect::Dissection& x, const qs::dissect::DissectOptions& o, int depth) {
    const auto share = leaf_area_shares(x);
    int n = 0;
    for (size_t i = 0; i < share.size(); ++i) {
      const auto& p = x.chart.patches[i];
      const int level = static_cast<int>(std::count(p.name.begin(), p.name.end(), '.'));
      n += p.stretch > o.tau && share[i] >= o.force_split_area && p.stop == qs::dissect::StopReason::MaxDepth &&
           level <= depth;
    }
    return n;
  };
  EXPECT_GT(large_at_depth(d_off, off, off.max_depth), 0) << "the test should exercise the rule";
  EXPECT_EQ(large_at_depth(d, on, on.max_depth + on.area_extra_depth - 1), 0);
  EXPECT_LT(after.largest_over_tau, before.largest_over_tau);
  int deepest = 0;
  for (const auto& n : d.tree) deepest = std::max(deepest, n.depth);
  EXPECT_GT(deepest, on.max_depth);
  EXPECT_TRUE(d.base.closed_conforming);
}

TEST(LongLimbs, AreaExtraDepthOutOfRangeIsRejected) {
  const qs::TriMesh m = qs::shapes::icosphere(2);
  for (int bad : {-1, 13}) {
    qs::dissect::DissectOptions o;
    o.area_extra_depth = bad;
    try {
      qs::dissect::dissect(m, std::nullopt, o);
      ADD_FAILURE() << "area_extra_depth " << bad << " accepted";
    } catch (const qs::InvalidInput& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("area_extra_depth"));
    }
  }
}

TEST(LongLimbs, AreaFractionsOutsideZeroOneAreRejected) {
  const qs::TriMesh m = qs::shapes::icosphere(2);
  for (double bad : {-0.1, 1.5, std::nan("")}) {
    qs::dissect::DissectOptions o;
    o.min_split_area = bad;
    try {
      qs::dissect::dissect(m, std::nullopt, o);
      ADD_FAILURE() << "min_split_area " << bad << " accepted";
    } catch (const qs::InvalidInput& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("min_split_area"));
    }
    o = {};
    o.force_split_area = bad;
    try {
      qs::dissect::dissect(m, std::nullopt, o);
      ADD_FAILURE() << "force_split_area " << bad << " accepted";
    } catch (const qs::InvalidInput& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("force_split_area"));
    }
  }
}

}  // namespace
