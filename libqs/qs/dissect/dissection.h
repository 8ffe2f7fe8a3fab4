#pragma once
// Dissection of one closed genus-0 mesh into quad patches by recursive quinary subdivision
// (paper sections 3.1-3.3), each patch parameterized onto the unit square.

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::dissect {

struct DissectOptions {
  /// A patch whose normalized L2 stretch (1 = isometric up to scale) exceeds tau is split.
  double tau = 3.0;
  int max_depth = 6;             ///< seed patches have depth 0
  int min_faces_to_split = 150;  ///< smaller patches are not split (stop reason "too_few_faces")
  /// The w rule: w = clamp(w_bias + log10(s_peak), w_min, w_max), s_peak the smoothed peak
  /// stretch (paper eq. 4 with psi = w_bias). With stretch normalized to 1 for an isometry, the
  /// peak of a patch worth splitting is well above 1, so the clamp decides in practice: w_max
  /// keeps the four outer children from becoming slivers (see the README).
  double w_bias = 0.45;
  double w_min = 0.5;
  double w_max = 0.65;
  /// The peak is clamped into [peak_margin, 1 - peak_margin]^2: a peak near a side would make
  /// the child along that side a thin strip whose own map to the square is badly stretched.
  double peak_margin = 0.35;
};

/// Why a patch over tau was left as it is.
enum class StopReason { None, MaxDepth, TooFewFaces, SplitFailed };
const char* stop_reason_name(StopReason r);

/// A leaf patch of the final dissection.
struct PatchInfo {
  std::string name;                ///< path in the quinary tree: "0", "1", "0.3", "0.3.4", ...
  std::array<int, 4> corners{};    ///< chart vertex ids, CCW: uv (0,0) (1,0) (1,1) (0,1)
  int faces = 0;
  double stretch = 0;              ///< normalized L2 stretch of its parameterization
  int flipped_faces = 0;
  int zero_area_faces = 0;
  double uv_area_sum = 0;
  StopReason stop = StopReason::None;  ///< set when stretch > tau
  std::string stop_detail;         ///< a sentence for SplitFailed
};

/// One node of the quinary tree (leaves and split nodes).
struct TreeNode {
  std::string name;
  int depth = 0;
  double stretch = 0;              ///< of the node's own parameterization
  bool split = false;              ///< children are name + ".0" .. ".4"
  Vec2 peak_uv = Vec2::Zero();     ///< split nodes: the peak point used
  double w = 0;                    ///< split nodes: the w used
};

/// The cut mesh with one patch label and one (u,v) per face corner.
struct Chart {
  TriMesh mesh;
  std::vector<int> face_patch;                ///< #F, index into `patches`
  std::vector<std::array<Vec2, 3>> face_uv;   ///< #F, wedge (u,v) in the face's patch
  std::vector<PatchInfo> patches;             ///< the leaves, sorted by name
};

/// The base domain: patch corners as vertices, patches as quads.
struct BaseDomain {
  std::vector<int> vertices;                  ///< base vertex -> chart vertex id
  std::vector<std::array<int, 4>> quads;      ///< per leaf patch (same order), base vertex ids
  int edges = 0;
  int euler_characteristic = 0;               ///< V - E + F
  bool closed_conforming = false;             ///< every quad side shared with exactly one other
};

struct Dissection {
  std::array<int, 4> seeds{};                 ///< input-mesh vertex ids
  std::vector<TreeNode> tree;                 ///< parents before children, siblings by name
  Chart chart;
  BaseDomain base;
  double max_stretch = 0;
};

/// Dissects a validated mesh. `seeds` are vertex ids of `mesh`; nullopt chooses them
/// automatically (choose_seeds). \throws InvalidInput for unroutable seeds, SolverError when a
/// parameterization fails.
Dissection dissect(const TriMesh& mesh, const std::optional<std::array<int, 4>>& seeds,
                   const DissectOptions& options = {}, const Context& context = {});

/// Builds and checks the base domain of a chart's leaves.
BaseDomain build_base_domain(const std::vector<PatchInfo>& patches);

}  // namespace qs::dissect
