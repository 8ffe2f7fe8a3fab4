#pragma once
// Branch matching between two curve skeletons (skeleton-guided DFI, section 4.2), in morph space
// (the target already aligned onto the source).
//
// Automatic: feature nodes (terminals, degree 1; junctions, degree >= 3) are matched greedily by
// increasing distance between their positions, normalized by the source's bounding-box diagonal,
// a terminal only to a terminal and a junction only to a junction (the paper votes over
// node-pair embeddings; ours is the nearest-first rule, which the alignment makes meaningful).
// Forced pairs (named landmarks on both shapes) are matched first, whatever their kind.
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
};

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
