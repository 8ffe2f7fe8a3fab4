#pragma once
// Branch matching between two curve skeletons (skeleton-guided DFI, section 4.2), in morph space
// (the target already aligned onto the source).
//
// Automatic: the feature nodes (terminals, degree 1; junctions, degree >= 3; the start of a pure
// cycle) are matched by voting (Au et al., "Electors voting for fast automatic shape
// correspondence", with the paper's Euclidean term). A candidate pair joins a terminal to a
// terminal or a junction to a junction whose centricities (mean geodesic distance along the
// skeleton to every point of it, over the skeleton's largest) differ by at most
// max_centricity_difference and whose positions, once the skeletons' centroids are made to
// coincide (the paper: same orientation, aligned by a translation), lie at most max_distance
// apart. Two candidates are consistent when they share no node and, between their nodes on either
// side, the geodesic path lengths agree (difference at most max_path_difference times the longer,
// or 0.05 of the diagonal), the numbers of junctions on those paths differ by at most one
// (topology), and the directions from one node to the other agree (angle at most
// max_angle_degrees where both are longer than 0.05 of the diagonal; spatial configuration).
// Every triple of mutually consistent candidates (an elector) votes for its three pairs with the
// product of their scores, each exp(-(euclidean / euclid_scale)^2 - (centricity difference /
// 0.1)^2). The pairs are then taken by decreasing vote (ties: nearest first), each only if it is
// consistent with every pair already taken. The fallback, nearest-first in the aligned space (a
// terminal to a terminal, a junction to a junction, at most max_distance apart), then matches the
// feature nodes the votes left, and is the whole rule with voting off.
// Forced pairs (named landmarks on both shapes) are matched first, whatever their kind, and the
// automatic pairs must be consistent with them too.
// Branches (the paper's figure 5): a branch with a terminal end is matched to the target branch
// that holds the terminal's match (cases 1-3, whatever the other ends); a branch between two
// junctions to a target branch whose two ends are matched to its own (case 6).

#include <string>
#include <vector>

#include "qs/dfi/skeleton.h"

namespace qs::dfi {

struct NodePair {
  int source = 0, target = 0;
  bool forced = false;  ///< from a named landmark
  std::string name;     ///< the landmark's name when forced
  double votes = 0;     ///< the electors' votes for it (0: forced, or taken nearest-first)
};

struct BranchPair {
  int source = 0, target = 0;  ///< indices into the branch lists
  bool reversed = false;       ///< the target branch runs from the match of source.b to that of source.a
};

struct SkeletonMatching {
  std::vector<NodePair> nodes;
  std::vector<BranchPair> branches;
};

struct MatchOptions {
  /// Feature nodes farther apart than this (times the source's bounding-box diagonal) stay unmatched.
  double max_distance = 0.5;
  bool voting = true;                      ///< false: nearest-first alone (and no consistency check)
  double max_centricity_difference = 0.25; ///< centricities are in (0, 1]
  double max_path_difference = 0.4;        ///< |g0 - g1| / max(g0, g1) between matched node pairs
  double max_angle_degrees = 60;           ///< between the directions of matched node pairs
  double euclid_scale = 0.15;              ///< the Euclidean term's scale (times the diagonal)
  long max_electors = 2000000;             ///< triples examined at most (in a fixed order)
};

/// Per node, the centricity: its mean geodesic distance along the skeleton to every point of it
/// (edges weighted by length) over the largest such mean; in (0, 1], 1 at the most eccentric node.
std::vector<double> centricity(const Skeleton& s);

/// \param forced node pairs that must be matched (e.g. from landmarks); nodes of any degree.
SkeletonMatching match_skeletons(const Skeleton& source, const std::vector<Branch>& source_branches,
                                 const Skeleton& target, const std::vector<Branch>& target_branches,
                                 const std::vector<NodePair>& forced, double source_diagonal,
                                 const MatchOptions& options = {});

/// The skeleton node nearest to p (lowest index on ties).
int nearest_node(const Skeleton& s, const Vec3& p);

/// Corresponding point pairs sampled along matched branches (section 4.2): the ends and
/// `per_branch` interior points at equal arc-length fractions; duplicates (shared ends) once.
struct AnchorPair {
  Vec3 source, target;
};
std::vector<AnchorPair> sample_anchors(const Skeleton& source, const std::vector<Branch>& source_branches,
                                       const Skeleton& target, const std::vector<Branch>& target_branches,
                                       const SkeletonMatching& matching, int per_branch);

}  // namespace qs::dfi
