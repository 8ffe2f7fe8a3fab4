// The voting matcher of the feature nodes (centricity, path length, topology, spatial
// configuration and the Euclidean term after a translation) against the nearest-first fallback,
// on hand-built skeletons.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "qs/dfi/matching.h"
#include "qs/dfi/skeleton.h"

using namespace qs;
using namespace qs::dfi;

namespace {

// A quadruped's skeleton: a spine from the front junction (0, 0) to the back junction (1, 0), a
// head and a tail, and four legs of different lengths (front left long, front right short, back
// left short, back right long), the legs in the xy plane. `stretch` scales x, `offset` moves it.
struct Animal {
  Skeleton s;
  std::map<std::string, int> node;  // role -> node index
};

Animal animal(double stretch, const Vec3& offset) {
  Animal a;
  const std::pair<const char*, Vec3> roles[] = {{"front", {0, 0, 0}},     {"back", {1, 0, 0}},      {"head", {-0.4, 0, 0.1}},
                                                {"tail", {1.4, 0, 0.2}},  {"front-left", {0, 0.6, 0}}, {"front-right", {0, -0.3, 0}},
                                                {"back-left", {1, 0.3, 0}}, {"back-right", {1, -0.6, 0}}};
  for (const auto& [name, p] : roles) {
    a.node[name] = static_cast<int>(a.s.nodes.size());
    a.s.nodes.push_back(Vec3(stretch * p.x(), p.y(), p.z()) + offset);
  }
  // The spine through two middle nodes, the rest direct.
  const int m1 = static_cast<int>(a.s.nodes.size());
  a.s.nodes.push_back(Vec3(stretch / 3, 0, 0) + offset);
  a.s.nodes.push_back(Vec3(2 * stretch / 3, 0, 0) + offset);
  auto n = [&](const char* r) { return a.node.at(r); };
  a.s.edges = {{n("front"), m1},        {m1, m1 + 1},          {m1 + 1, n("back")},     {n("front"), n("head")},
               {n("back"), n("tail")},  {n("front"), n("front-left")}, {n("front"), n("front-right")},
               {n("back"), n("back-left")}, {n("back"), n("back-right")}};
  a.s.node_vertices.resize(a.s.nodes.size());
  return a;
}

// Role of the target node each source role was matched to ("" when unmatched).
std::map<std::string, std::string> roles_matched(const Animal& src, const Animal& dst, const SkeletonMatching& m) {
  std::map<std::string, std::string> out;
  for (const auto& [role, i] : src.node) {
    out[role] = "";
    for (const NodePair& p : m.nodes)
      if (p.source == i)
        for (const auto& [r2, j] : dst.node)
          if (j == p.target) out[role] = r2;
  }
  return out;
}

}  // namespace

// The target is the source moved sideways by half its width (and stretched 10% along the spine):
// nearest-first pairs the source's front-left foot with the target's front-right one (0.4 apart
// against 0.5) and the back-left with the back-right; the votes keep every part with its own.
TEST(Matching, VotingKeepsLeftAndRightWhereNearestFirstSwapsThem) {
  const Animal a = animal(1.0, Vec3::Zero());
  const Animal b = animal(1.1, Vec3(0, 0.5, 0));
  const auto b0 = skeleton_branches(a.s), b1 = skeleton_branches(b.s);
  const double diagonal = 2.2;
  MatchOptions nearest;
  nearest.voting = false;
  const auto swapped = roles_matched(a, b, match_skeletons(a.s, b0, b.s, b1, {}, diagonal, nearest));
  EXPECT_EQ(swapped.at("front-left"), "front-right");  // the construction does fool nearest-first
  const SkeletonMatching voted = match_skeletons(a.s, b0, b.s, b1, {}, diagonal);
  const auto roles = roles_matched(a, b, voted);
  for (const auto& [role, matched] : roles) EXPECT_EQ(matched, role) << role;
  EXPECT_EQ(voted.branches.size(), b0.size());  // every branch, each with its own
  for (const BranchPair& p : voted.branches) {
    const Vec3 d0 = a.s.nodes[b0[p.source].b] - a.s.nodes[b0[p.source].a];
    const Vec3 d1 = b.s.nodes[b1[p.target].b] - b.s.nodes[b1[p.target].a];
    EXPECT_GT((p.reversed ? -d1 : d1).dot(d0), 0) << p.source << " -> " << p.target;
  }
  for (const NodePair& p : voted.nodes) EXPECT_GT(p.votes, 0);
}

// A landmark forces its pair; the votes then keep the rest consistent with it, and a pair
// inconsistent with the forced one is not taken.
TEST(Matching, ForcedPairsComeFirstAndTheVotesAgreeWithThem) {
  const Animal a = animal(1.0, Vec3::Zero());
  const Animal b = animal(1.0, Vec3(0, 0.5, 0));
  const auto b0 = skeleton_branches(a.s), b1 = skeleton_branches(b.s);
  const SkeletonMatching m = match_skeletons(a.s, b0, b.s, b1, {{a.node.at("head"), b.node.at("head"), true, "nose"}}, 2.2);
  ASSERT_FALSE(m.nodes.empty());
  EXPECT_TRUE(m.nodes[0].forced);
  EXPECT_EQ(m.nodes[0].name, "nose");
  const auto roles = roles_matched(a, b, m);
  for (const auto& [role, matched] : roles) EXPECT_EQ(matched, role) << role;
}

TEST(Matching, CentricityIsHighestAtTheExtremities) {
  const Animal a = animal(1.0, Vec3::Zero());
  const std::vector<double> c = centricity(a.s);
  for (double x : c) {
    EXPECT_GT(x, 0);
    EXPECT_LE(x, 1);
  }
  EXPECT_LT(c[a.node.at("front")], c[a.node.at("front-left")]);
  EXPECT_LT(c[a.node.at("front")], c[a.node.at("tail")]);
  EXPECT_DOUBLE_EQ(*std::max_element(c.begin(), c.end()), 1.0);
}

// The same along the spine: the target moved forward by more than half the spine, so that
// nearest-first pairs the source's back junction with the target's front one; the votes keep
// front with front and back with back.
TEST(Matching, VotingKeepsFrontAndBackWhereNearestFirstSwapsThem) {
  const Animal a = animal(1.0, Vec3::Zero());
  const Animal b = animal(1.1, Vec3(0.6, 0, 0));
  const auto b0 = skeleton_branches(a.s), b1 = skeleton_branches(b.s);
  MatchOptions nearest;
  nearest.voting = false;
  const auto swapped = roles_matched(a, b, match_skeletons(a.s, b0, b.s, b1, {}, 2.2, nearest));
  EXPECT_EQ(swapped.at("back"), "front");
  const auto roles = roles_matched(a, b, match_skeletons(a.s, b0, b.s, b1, {}, 2.2));
  for (const auto& [role, matched] : roles) EXPECT_EQ(matched, role) << role;
}
