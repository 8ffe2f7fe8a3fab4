#pragma once
// Plain linear blending of the N position arrays of a semi-regular set (paper section 5: the
// remeshes share one connectivity, so a morph is a per-vertex affine combination).

#include <string>
#include <vector>

#include "qs/core/mesh.h"
#include "qs/remesh/semi_regular.h"

namespace qs::morph {

/// One frame of a path: its barycentric weights over the shapes and where it lies on the path.
struct PathFrame {
  std::vector<double> weights;  ///< #shapes, >= 0, summing to 1
  double s = 0;                 ///< path parameter in [0, #stops - 1]: stop k is at s = k
  int leg = 0;                  ///< the leg it lies on: from stop `leg` to stop `leg + 1`
  double t = 0;                 ///< position on that leg in [0, 1]
};

/// `frames` frames along the path stops[0] -> stops[1] -> ... (shape indices, a shape may repeat).
/// Frames are uniform in the path parameter: frame f is at s = f (S - 1) / (frames - 1), S the
/// number of stops, so every leg gets the same share of frames and a stop is hit exactly when
/// (frames - 1) is a multiple of (S - 1). Frame 0 is exactly stops[0], the last frame exactly
/// stops[S - 1]. On leg k at t: weight (1 - t) on stops[k], t on stops[k + 1] (summed when equal).
/// \throws InvalidInput when frames < 2, fewer than 2 stops, or a stop is not in [0, num_shapes).
std::vector<PathFrame> path_frames(int num_shapes, const std::vector<int>& stops, int frames);

/// Checks barycentric weights: one per shape, each finite and >= 0, summing to 1 within 1e-6.
/// \throws InvalidInput saying which rule is broken, with the numbers.
void check_weights(const std::vector<double>& weights, int num_shapes);

/// sum_i weights[i] * positions[i], skipping zero weights: a weight vector (0, .., 1, .., 0)
/// gives that shape's positions bit-exactly. \throws InvalidInput (check_weights; the arrays
/// must have one size).
std::vector<Vec3> blend(const std::vector<std::vector<Vec3>>& positions, const std::vector<double>& weights);

/// The same for a set.
inline std::vector<Vec3> blend(const remesh::SemiRegularSet& set, const std::vector<double>& weights) {
  return blend(set.positions, weights);
}

/// How a shape is placed onto the base before blending (the files of different characters rarely
/// share a pose, a facing or a scale).
enum class Align { None, Rigid, Similarity };
/// "none", "rigid", "similarity". \throws InvalidInput for another name.
Align align_from_name(const std::string& name);

/// `shape` moved by the rotation (and, for Similarity, the uniform scale) and translation that
/// best map it onto `base` in the least-squares sense over corresponding vertices (Umeyama 1991;
/// the remeshes share one vertex numbering). None returns shape unchanged.
/// \throws InvalidInput when the arrays differ in size or are empty.
std::vector<Vec3> align_to(const std::vector<Vec3>& shape, const std::vector<Vec3>& base, Align how);

/// Index of `name` in `names`. \throws InvalidInput listing the known names.
int shape_index(const std::vector<std::string>& names, const std::string& name);

}  // namespace qs::morph
