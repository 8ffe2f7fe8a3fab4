// Squeezed protrusions (DissectOptions::protrusion_stretch): a node whose map squeezes a
// protrusion into a point of the square is split with the protrusion in its centre child (the
// peak_margin clamp alone can leave it in an outer child, split after split around the same two
// corners, and the children there end as strips). Only such nodes change: a shape without
// protrusions gets the same tree with the rule on or off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "check_dissection.h"
#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/shapes/shapes.h"

namespace {

using qs::dissect::DissectOptions;
using qs::dissect::TreeNode;

DissectOptions with_protrusion_stretch(double s) {
  DissectOptions o;
  o.protrusion_stretch = s;
  return o;
}

// Split nodes whose own stretch exceeds `s`.
std::vector<const TreeNode*> squeezed_splits(const std::vector<TreeNode>& tree, double s) {
  std::vector<const TreeNode*> out;
  for (const auto& n : tree)
    if (n.split && n.stretch > s) out.push_back(&n);
  return out;
}

// Whether q lies at least `margin` inside the centre child's square [w c, w c + 1 - w]^2.
bool in_centre(const qs::Vec2& q, const qs::Vec2& c, double w, double margin) {
  for (int d = 0; d < 2; ++d)
    if (q[d] < w * c[d] + margin || q[d] > w * c[d] + 1 - w - margin) return false;
  return true;
}

// Whether a centre square 0.1 off the sides can hold q 0.05 inside it.
bool holdable(const qs::Vec2& q, double w) {
  for (int d = 0; d < 2; ++d)
    if (q[d] < 0.1 + 0.05 || q[d] > 1 - 0.1 - 0.05 || 1 - w < 0.1) return false;
  return true;
}

// A blob with eight arms (5120 faces): with automatic seeds some arms lie inside seed patches,
// squeezed by their maps (node stretch 30-1000, under the default bound, so the tests set a bound
// of 30), some with their peak near a side of the square, where the peak_margin clamp leaves it
// outside the centre child.
qs::TriMesh arms() { return qs::shapes::star_blob(8, 2.5, 4); }
constexpr double kBound = 30;

TEST(Protrusion, SqueezedNodesHoldTheirPeakInTheCentreChild) {
  const qs::TriMesh m = arms();
  const DissectOptions on = with_protrusion_stretch(kBound);
  // Off: the peak_margin clamp leaves some squeezed node's peak outside its centre child (what
  // the rule is for; else this shape would not test it).
  const auto off = qs::dissect::dissect(m, std::nullopt, with_protrusion_stretch(0));
  int outside_off = 0;
  for (const TreeNode* n : squeezed_splits(off.tree, kBound))
    outside_off += !in_centre(n->raw_peak_uv, n->peak_uv, n->w, 0.0) && holdable(n->raw_peak_uv, n->w);
  ASSERT_GT(outside_off, 0) << "the test shape must have a squeezed node whose peak the clamp leaves outside";
  // On: every squeezed node whose peak can be held holds it 0.05 inside, its centre square 0.1
  // off the sides.
  const auto d = qs::dissect::dissect(m, std::nullopt, on);
  const auto squeezed = squeezed_splits(d.tree, kBound);
  ASSERT_FALSE(squeezed.empty());
  int held = 0;
  for (const TreeNode* n : squeezed) {
    if (!holdable(n->raw_peak_uv, n->w)) continue;
    ++held;
    EXPECT_TRUE(in_centre(n->raw_peak_uv, n->peak_uv, n->w, 0.05 - 1e-12))
        << n->name << " peak (" << n->raw_peak_uv.transpose() << ") centre (" << n->peak_uv.transpose() << ") w " << n->w;
    for (int k = 0; k < 2; ++k) {
      EXPECT_GE(n->w * n->peak_uv[k], 0.1 - 1e-12) << n->name;
      EXPECT_LE(n->w * n->peak_uv[k] + 1 - n->w, 0.9 + 1e-12) << n->name;
    }
  }
  EXPECT_GT(held, 0);
  // Every leaf bijective, the chart and base domain valid, the seeds at patch corners.
  qs::testing::check_dissection(d, m.num_faces());
  for (const auto& p : d.chart.patches) EXPECT_EQ(p.flipped_faces + p.zero_area_faces, 0) << p.name;
  for (int s : d.seeds) {
    bool corner = false;
    for (const auto& p : d.chart.patches)
      for (int c : p.corners) corner = corner || c == s;
    EXPECT_TRUE(corner) << "seed " << s;
  }
}

TEST(Protrusion, ShapeWithoutProtrusionsKeepsItsTree) {
  // An ellipsoid: every node's stretch is far below the bound, so the rule never applies.
  const qs::TriMesh m = qs::shapes::ellipsoid(1.0, 0.6, 0.35, 4);
  const DissectOptions on;
  const auto a = qs::dissect::dissect(m, std::nullopt, on);
  const auto b = qs::dissect::dissect(m, std::nullopt, with_protrusion_stretch(0));
  ASSERT_TRUE(squeezed_splits(a.tree, on.protrusion_stretch).empty());
  ASSERT_EQ(a.tree.size(), b.tree.size());
  for (size_t i = 0; i < a.tree.size(); ++i) {
    EXPECT_EQ(a.tree[i].name, b.tree[i].name);
    EXPECT_EQ(a.tree[i].w, b.tree[i].w) << a.tree[i].name;
    EXPECT_EQ(a.tree[i].peak_uv, b.tree[i].peak_uv) << a.tree[i].name;
  }
  EXPECT_EQ(a.chart.mesh.positions, b.chart.mesh.positions);
  EXPECT_EQ(a.chart.face_uv, b.chart.face_uv);
}

TEST(Protrusion, NodesUnderTheBoundKeepTheRule) {
  // The same arms at the default bound (1000): no node is that squeezed, so nothing changes.
  const qs::TriMesh m = arms();
  const DissectOptions on;
  ASSERT_EQ(on.protrusion_stretch, 1000);
  const auto a = qs::dissect::dissect(m, std::nullopt, on);
  const auto b = qs::dissect::dissect(m, std::nullopt, with_protrusion_stretch(0));
  ASSERT_TRUE(squeezed_splits(a.tree, on.protrusion_stretch).empty());
  ASSERT_FALSE(squeezed_splits(a.tree, kBound).empty());  // squeezed nodes there are, under the bound
  ASSERT_EQ(a.tree.size(), b.tree.size());
  for (size_t i = 0; i < a.tree.size(); ++i) {
    EXPECT_EQ(a.tree[i].name, b.tree[i].name);
    EXPECT_EQ(a.tree[i].peak_uv, b.tree[i].peak_uv) << a.tree[i].name;
  }
  EXPECT_EQ(a.chart.face_uv, b.chart.face_uv);
}

TEST(Protrusion, FeaturesStayExactAndTheResultIsDeterministic) {
  // Two copies of the blob, the second stretched, with a feature on the body: the squeezed nodes
  // are split the same way in both, the feature ends at one (u,v) in both.
  const qs::TriMesh m0 = arms();
  qs::TriMesh m1 = m0;
  for (auto& x : m1.positions) x = qs::Vec3(1.1 * x.x(), 0.9 * x.y(), x.z());
  // The feature: the vertex farthest from every arm (on the body).
  const auto dirs = qs::shapes::fibonacci_directions(8);
  auto nearest_arm = [&](int v) {
    double c = -1;
    for (const auto& a : dirs) c = std::max(c, m0.positions[v].normalized().dot(a));
    return c;
  };
  int feature = 0;
  for (int v = 0; v < m0.num_vertices(); ++v)
    if (nearest_arm(v) < nearest_arm(feature)) feature = v;
  std::vector<qs::dissect::MeshToDissect> in(2);
  in[0].mesh = &m0;
  in[1].mesh = &m1;
  in[0].name = "a";
  in[1].name = "b";
  for (auto& x : in) x.features.push_back({"tip", feature, {}});
  const DissectOptions on = with_protrusion_stretch(kBound);
  const auto s1 = qs::dissect::dissect_set(in, on);
  const auto s2 = qs::dissect::dissect_set(in, on);
  const auto squeezed = squeezed_splits(s1.tree, kBound);
  ASSERT_FALSE(squeezed.empty());
  for (const TreeNode* n : squeezed) {
    if (holdable(n->raw_peak_uv, n->w) && n->features == 0) {
      EXPECT_TRUE(in_centre(n->raw_peak_uv, n->peak_uv, n->w, 0.05 - 1e-12)) << n->name;
    }
  }
  ASSERT_EQ(s1.meshes.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    qs::testing::check_dissection(s1.meshes[i], (i == 0 ? m0 : m1).num_faces());
    ASSERT_EQ(s1.meshes[i].features.size(), 1u);
    EXPECT_EQ(s1.meshes[i].chart.mesh.positions[s1.meshes[i].features[0].vertex], (i == 0 ? m0 : m1).positions[feature]);
    // Determinism: the same chart, bit for bit.
    EXPECT_EQ(s1.meshes[i].chart.mesh.positions, s2.meshes[i].chart.mesh.positions);
    EXPECT_EQ(s1.meshes[i].chart.face_uv, s2.meshes[i].chart.face_uv);
  }
  EXPECT_EQ(s1.meshes[0].features[0].patch, s1.meshes[1].features[0].patch);
  EXPECT_EQ(s1.meshes[0].features[0].uv, s1.meshes[1].features[0].uv);
}

TEST(Protrusion, NegativeOrNanBoundIsRejected) {
  const qs::TriMesh m = qs::shapes::icosphere(2);
  for (double bad : {-1.0, std::nan("")}) {
    try {
      qs::dissect::dissect(m, std::nullopt, with_protrusion_stretch(bad));
      ADD_FAILURE() << "accepted protrusion_stretch " << bad;
    } catch (const qs::InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find("protrusion_stretch"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
