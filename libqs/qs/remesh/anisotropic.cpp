// The anisotropic even remesh: the stages in order (tree, cuts, smoothing, sliding, flips).

#include "qs/remesh/anisotropic.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/remesh/anisotropic_detail.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"

namespace qs::remesh {

using namespace aniso;

AnisotropicRemesh remesh_anisotropic(const std::vector<const dissect::Chart*>& charts, const AnisotropicOptions& options,
                                     const Context& context) {
  if (!(options.max_area > 0) || !std::isfinite(options.max_area))
    throw InvalidInput("remesh: the anisotropic remesh's area bound must be a positive share of the surface, got " +
                       std::to_string(options.max_area));
  if (!(options.max_aspect >= 1.5) || !std::isfinite(options.max_aspect))
    throw InvalidInput("remesh: the anisotropic remesh's aspect bound must be a finite number >= 1.5 (a cell's "
                       "longer side over its shorter on the surface), got " + std::to_string(options.max_aspect));
  if (options.max_level < 0 || options.max_level > kMaxAnisotropicLevel)
    throw InvalidInput("remesh: max level " + std::to_string(options.max_level) + " is out of range; expected 0.." +
                       std::to_string(kMaxAnisotropicLevel));
  if (options.flip_rounds < 0 || options.flip_rounds > 10)
    throw InvalidInput("remesh: flip rounds " + std::to_string(options.flip_rounds) + " are out of range; expected 0..10");
  if (options.smooth_iterations < 0 || options.smooth_iterations > 100)
    throw InvalidInput("remesh: smoothing sweeps " + std::to_string(options.smooth_iterations) +
                       " are out of range; expected 0..100");
  if (!(options.smooth_below >= 0 && options.smooth_below <= 60))
    throw InvalidInput("remesh: the smoothing's angle bound must be 0..60 degrees, got " +
                       std::to_string(options.smooth_below));
  if (charts.empty()) throw InvalidInput("remesh: no charts to remesh");
  const std::vector<ChartSampler> samplers = set_samplers(charts, context);
  const BaseTopology& topology = samplers[0].topology();

  AnisotropicRemesh out;
  build_leaves(samplers, options, context, out);
  for (double r : out.leaf_aspect) out.stats.max_leaf_aspect = std::max({out.stats.max_leaf_aspect, r, 1.0 / r});
  for (const auto& n : out.leaves) out.stats.finest_level = std::max({out.stats.finest_level, n.lu, n.lv});

  std::vector<LeafCut> cuts;
  std::vector<size_t> templates;
  out.remesh.connectivity = leaf_connectivity(topology, out.leaves, cuts, templates, out.stats.fan_leaves,
                                                  out.face_leaf);
  for (size_t m = 0; m < samplers.size(); ++m) {
    context.report("remesh", 0.7 + 0.3 * m / samplers.size());
    out.remesh.positions.push_back(sample_positions(samplers[m], out.remesh.connectivity, context));
  }
  auto& faces = out.remesh.connectivity.faces;
  for (const auto& cut : cuts)
    recut_cell_best_angle(faces[cut.first_face], faces[cut.first_face + 1], cut.diag02, out.remesh.positions);
  // The template cells' corners A, M, B, C, D (emitted as (A, M, D), (M, B, C), (M, C, D)).
  std::vector<std::array<int, 5>> pentagons;
  pentagons.reserve(templates.size());
  for (size_t first : templates) {
    const Tri &f0 = faces[first], &f1 = faces[first + 1];
    pentagons.push_back({f0[0], f0[1], f1[1], f1[2], f0[2]});
  }
  for (size_t k = 0; k < templates.size(); ++k)
    recut_template_best_angle(&faces[templates[k]], pentagons[k], out.remesh.positions);
  // The sides slide in a set only (docs/algorithms.md).
  const bool slide = options.slide_sides && samplers.size() > 1;
  if (options.smooth_iterations > 0) {
    context.check_cancel();
    out.stats.smoothed_moves = smooth_interior(samplers, out.remesh.connectivity, out.remesh.positions,
                                               options.smooth_iterations, options.smooth_below);
    if (slide)
      out.stats.slid_moves += slide_sides(samplers, out.remesh.connectivity, out.remesh.positions,
                                          options.smooth_iterations, options.smooth_below);
    // The cells' diagonals and templates again for the moved vertices. A moved cell need not be
    // convex in (u,v) any more, so a new cut is kept only where every corner is inside one patch
    // (one uv frame) and its triangles stay counter-clockwise there; elsewhere the cut the
    // smoothing checked stays.
    const auto& conn = out.remesh.connectivity;
    auto ccw_in_one_patch = [&](const Tri* f, int n) {
      const int patch = conn.vertex_patch[f[0][0]];
      for (int i = 0; i < n; ++i) {
        for (int v : f[i])
          if (conn.vertex_patch[v] != patch || !patch_interior(conn, v)) return false;
        const Vec2 &a = conn.vertex_uv[f[i][0]], &b = conn.vertex_uv[f[i][1]], &c = conn.vertex_uv[f[i][2]];
        if (!(cross2(b - a, c - a) > 0)) return false;
      }
      return true;
    };
    // (f1 starts at f0's first corner: cut 0-2.) A cell has two cuts: the other one is taken only
    // where it is accepted.
    for (const auto& cut : cuts) {
      Tri &f0 = faces[cut.first_face], &f1 = faces[cut.first_face + 1];
      const Tri k0 = f0, k1 = f1;
      recut_cell_best_angle(f0, f1, f1[0] == f0[0], out.remesh.positions);
      const Tri both[2] = {f0, f1};
      if ((f0 != k0 || f1 != k1) && !ccw_in_one_patch(both, 2)) f0 = k0, f1 = k1;
    }
    for (size_t k = 0; k < templates.size(); ++k)
      recut_template_best_angle(&faces[templates[k]], pentagons[k], out.remesh.positions,
                                [&](const std::array<Tri, 3>& cut) { return ccw_in_one_patch(cut.data(), 3); });
  }
  // Rounds of edge flips on the surface, each but the last followed by the interior smoothing of
  // the flipped rings.
  for (int r = 0; r < options.flip_rounds; ++r) {
    context.check_cancel();
    std::vector<char> touched(out.remesh.connectivity.num_vertices(), 0);
    out.stats.flips +=
        flip_for_angles(samplers, out.remesh.connectivity, out.remesh.positions, options.smooth_below, touched);
    if (r + 1 < options.flip_rounds) {
      out.stats.smoothed_moves += smooth_interior(samplers, out.remesh.connectivity, out.remesh.positions,
                                                  options.smooth_iterations, options.smooth_below, &touched);
      if (slide)
        out.stats.slid_moves += slide_sides(samplers, out.remesh.connectivity, out.remesh.positions,
                                            options.smooth_iterations, options.smooth_below, &touched);
    }
  }
  context.report("remesh", 1.0);
  return out;
}

AnisotropicOptions anisotropic_options(int level, int patches, double share_sum) {
  if (level < 0 || level > kMaxAnisotropicLevel)
    throw InvalidInput("remesh: level " + std::to_string(level) + " is out of range for the anisotropic remesh; "
                       "expected 0.." + std::to_string(kMaxAnisotropicLevel));
  if (patches < 1) throw InvalidInput("remesh: " + std::to_string(patches) + " patches; expected at least 1");
  if (!(share_sum >= 1) || !std::isfinite(share_sum))
    throw InvalidInput("remesh: the patches' largest shares of the surface add up to " + std::to_string(share_sum) +
                       "; expected a finite number >= 1");
  AnisotropicOptions o;
  o.max_area = kAnisoAreaFactor * share_sum / (static_cast<double>(patches) * std::ldexp(1.0, 2 * level));
  o.max_level = std::min(level + 6, kMaxAnisotropicLevel);
  return o;
}

AnisotropicRemesh remesh_even_anisotropic(const std::vector<const dissect::Chart*>& charts, int level,
                                          const Context& context) {
  if (charts.empty() || charts.front() == nullptr) throw InvalidInput("remesh: no charts to remesh");
  double sum = 0;
  for (double a : patch_area_shares(charts)) sum += a;
  return remesh_anisotropic(
      charts, anisotropic_options(level, static_cast<int>(charts.front()->patches.size()), std::max(sum, 1.0)), context);
}

}  // namespace qs::remesh
