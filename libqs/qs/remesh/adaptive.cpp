#include "qs/remesh/adaptive.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_set>

#include "qs/core/error.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"

namespace qs::remesh {

namespace {

constexpr int kDirI[4] = {0, 1, 0, -1}, kDirJ[4] = {-1, 0, 1, 0};  // side d of a node: bottom, right, top, left

std::uint64_t key(int i, int j) { return (static_cast<std::uint64_t>(i) << 32) | static_cast<std::uint32_t>(j); }

// Split sets per patch and level, with the neighbour rule across patch sides.
class Forest {
 public:
  Forest(const BaseTopology& t, int levels)
      : t_(&t), split_(t.num_patches(), std::vector<std::unordered_set<std::uint64_t>>(std::max(levels, 1))) {}

  int levels() const { return static_cast<int>(split_[0].size()); }
  bool is_split(const QuadNode& n) const {
    return n.level < levels() && split_[n.patch][n.level].count(key(n.i, n.j)) > 0;
  }
  bool exists(const QuadNode& n) const { return n.level == 0 || is_split({n.patch, n.level - 1, n.i / 2, n.j / 2}); }
  bool split(const QuadNode& n) { return split_[n.patch][n.level].insert(key(n.i, n.j)).second; }

  // The same-level node across side d of n (possibly in the twin patch).
  QuadNode neighbour(const QuadNode& n, int d) const {
    const int size = 1 << n.level;
    const int i = n.i + kDirI[d], j = n.j + kDirJ[d];
    if (i >= 0 && i < size && j >= 0 && j < size) return {n.patch, n.level, i, j};
    const int s = d == 0 ? n.i : d == 1 ? n.j : d == 2 ? size - 1 - n.i : size - 1 - n.j;
    const PatchSide tw = t_->twin(n.patch, d);
    const int r = size - 1 - s;
    switch (tw.side) {
      case 0: return {tw.patch, n.level, r, 0};
      case 1: return {tw.patch, n.level, size - 1, r};
      case 2: return {tw.patch, n.level, size - 1 - r, size - 1};
      default: return {tw.patch, n.level, 0, size - 1 - r};
    }
  }

  // Makes n a node by splitting its missing ancestors; returns how many splits that took.
  int ensure_exists(const QuadNode& n) {
    if (n.level == 0) return 0;
    const QuadNode parent{n.patch, n.level - 1, n.i / 2, n.j / 2};
    if (is_split(parent)) return 0;
    const int added = ensure_exists(parent);
    split(parent);
    return added + 1;
  }

  // 2:1 balance; returns the number of splits added.
  int balance() {
    int added = 0;
    for (int k = levels(); k >= 2; --k)  // nodes of level k exist where level k-1 is split
      for (int p = 0; p < t_->num_patches(); ++p) {
        std::vector<std::uint64_t> parents(split_[p][k - 1].begin(), split_[p][k - 1].end());
        for (const std::uint64_t kk : parents) {
          const QuadNode g{p, k - 1, static_cast<int>(kk >> 32), static_cast<int>(kk & 0xffffffffu)};
          for (int d = 0; d < 4; ++d) added += ensure_exists(neighbour(g, d));
        }
      }
    return added;
  }

  std::vector<QuadNode> split_nodes() const {
    std::vector<QuadNode> out;
    for (int p = 0; p < t_->num_patches(); ++p)
      for (int l = 0; l < levels(); ++l)
        for (const std::uint64_t kk : split_[p][l])
          out.push_back({p, l, static_cast<int>(kk >> 32), static_cast<int>(kk & 0xffffffffu)});
    std::sort(out.begin(), out.end());
    return out;
  }

  void leaves(const QuadNode& n, std::vector<QuadNode>& out) const {
    if (!is_split(n)) {
      out.push_back(n);
      return;
    }
    for (int b = 0; b < 2; ++b)
      for (int a = 0; a < 2; ++a) leaves({n.patch, n.level + 1, 2 * n.i + a, 2 * n.j + b}, out);
  }

 private:
  const BaseTopology* t_;
  std::vector<std::vector<std::unordered_set<std::uint64_t>>> split_;  // [patch][level] -> (i, j)
};

// The diagonal of a node without T-vertex: true = C0-C2, false = C1-C3.
bool node_diagonal02(const BaseTopology& t, const QuadNode& n) {
  if (n.level == 0) return t.level0_diagonal02[n.patch];
  const int half = 1 << (n.level - 1);
  return (n.i < half) == (n.j < half);
}

void check_node(const BaseTopology& t, const QuadNode& n) {
  if (n.patch < 0 || n.patch >= t.num_patches() || n.level < 0 || n.level >= kMaxAdaptiveLevel || n.i < 0 ||
      n.j < 0 || n.i >= (1 << n.level) || n.j >= (1 << n.level))
    throw InvalidInput("remesh: quadtree node (patch " + std::to_string(n.patch) + ", level " + std::to_string(n.level) +
                       ", " + std::to_string(n.i) + ", " + std::to_string(n.j) + ") cannot be split; expected a patch 0.." +
                       std::to_string(t.num_patches() - 1) + ", a level 0.." + std::to_string(kMaxAdaptiveLevel - 1) +
                       " and 0 <= i, j < 2^level");
}

QuadForest finish(const BaseTopology& t, const Forest& f) {
  QuadForest out;
  out.split = f.split_nodes();
  for (int p = 0; p < t.num_patches(); ++p) f.leaves({p, 0, 0, 0}, out.leaves);
  for (const auto& n : out.leaves) out.max_level = std::max(out.max_level, n.level);
  return out;
}

// ---- Geometry of the error measure ---------------------------------------------------------

// Squared distance from p to triangle abc (Ericson, Real-Time Collision Detection 5.1.5).
double point_triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (ap - (d1 / (d1 - d3)) * ab).squaredNorm();
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (ap - (d2 / (d2 - d6)) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)).squaredNorm();
  const double sum = va + vb + vc;
  if (!(sum > 0)) {  // degenerate triangle: nearest of its edges
    auto seg = [&](const Vec3& x, const Vec3& y) {
      const Vec3 xy = y - x;
      const double l2 = xy.squaredNorm();
      const double s = l2 > 0 ? std::clamp((p - x).dot(xy) / l2, 0.0, 1.0) : 0.0;
      return (p - x - s * xy).squaredNorm();
    };
    return std::min({seg(a, b), seg(b, c), seg(c, a)});
  }
  const double v = vb / sum, w = vc / sum;
  return (p - (a + v * ab + w * ac)).squaredNorm();
}

struct Sample {
  Vec2 uv;
  Vec3 x;
};

/// Re-cuts every leaf without a T-vertex along the diagonal whose two triangles have the larger
/// smallest angle over the set (uniform.h's DiagonalRule::BestAngle, with the same exceptions: a
/// leaf of level 0, a leaf at a patch corner that is a base vertex of valence 2, and at level 1 a
/// leaf of a patch with such a corner keep the pattern's diagonal, whose other diagonal another
/// patch may join too). Faces are in adaptive_connectivity's order.
void choose_leaf_diagonals(const BaseTopology& t, const QuadForest& forest, const Forest& f,
                           SemiRegularConnectivity& c, const std::vector<std::vector<Vec3>>& positions) {
  size_t face = 0;
  for (const auto& n : forest.leaves) {
    int nt = 0;
    for (int d = 0; d < 4; ++d) nt += f.is_split(f.neighbour(n, d));
    const size_t first = face;
    face += nt == 0 ? 2 : nt == 1 ? 3 : 4 + nt;
    if (nt != 0 || n.level == 0) continue;
    const int size = 1 << n.level;
    if ((n.i == 0 || n.i == size - 1) && (n.j == 0 || n.j == size - 1)) {
      const int k = n.j == 0 ? (n.i == 0 ? 0 : 1) : (n.i == 0 ? 3 : 2);
      if (t.valence[t.quads[n.patch][k]] < 3) continue;
      if (size == 2) {
        bool free = true;
        for (int q = 0; q < 4; ++q) free = free && t.valence[t.quads[n.patch][q]] >= 3;
        if (!free) continue;
      }
    }
    Tri& f0 = c.faces[first];
    Tri& f1 = c.faces[first + 1];
    const bool diag02 = node_diagonal02(t, n);
    recut_cell_best_angle(f0, f1, diag02, positions);
  }
}

// Per mesh: the samplers and the chart vertices of each patch with their uv there.
struct MeshData {
  const ChartSampler* sampler = nullptr;
  std::vector<Sample> samples;      // patch by patch
  std::vector<int> patch_begin;     // #P + 1
  double inv_diagonal = 0;
  double inv_area = 0;              // 1 / the chart's surface area
};

// `with_vertices` false (the size rule needs no chart vertices): every patch's range is empty.
MeshData gather_samples(const ChartSampler& sampler, bool with_vertices) {
  const auto& chart = sampler.chart();
  struct Entry {
    int patch, vertex;
    Vec2 uv;
  };
  std::vector<Entry> e;
  if (with_vertices) e.reserve(3 * chart.mesh.faces.size());
  for (int f = 0; f < (with_vertices ? chart.mesh.num_faces() : 0); ++f)
    for (int k = 0; k < 3; ++k) e.push_back({chart.face_patch[f], chart.mesh.faces[f][k], chart.face_uv[f][k]});
  std::sort(e.begin(), e.end(), [](const Entry& a, const Entry& b) {
    return a.patch != b.patch ? a.patch < b.patch : a.vertex < b.vertex;
  });
  MeshData md;
  md.sampler = &sampler;
  md.patch_begin.assign(sampler.num_patches() + 1, 0);
  for (size_t i = 0; i < e.size(); ++i) {
    if (i > 0 && e[i].patch == e[i - 1].patch && e[i].vertex == e[i - 1].vertex) continue;
    md.samples.push_back({e[i].uv, chart.mesh.positions[e[i].vertex]});
    ++md.patch_begin[e[i].patch + 1];
  }
  for (int p = 0; p < sampler.num_patches(); ++p) md.patch_begin[p + 1] += md.patch_begin[p];
  const double diag = sampler.bbox_diagonal();
  md.inv_diagonal = diag > 0 ? 1.0 / diag : 0.0;
  double area = 0;
  for (int f = 0; f < chart.mesh.num_faces(); ++f) area += face_area(chart.mesh, f);
  md.inv_area = area > 0 ? 1.0 / area : 0.0;
  return md;
}

// Error-driven refinement of one patch, all meshes together.
class Refiner {
 public:
  Refiner(const BaseTopology& t, std::vector<MeshData>& meshes, const AdaptiveOptions& o, Forest& forest,
          AdaptiveStats& stats)
      : t_(t), meshes_(meshes), o_(o), forest_(forest), stats_(stats) {}

  void refine_patch(int p) {
    const size_t nm = meshes_.size();
    std::vector<std::array<Vec3, 4>> corners(nm);
    std::vector<std::array<int, 2>> ranges(nm);
    for (size_t m = 0; m < nm; ++m) {
      for (int k = 0; k < 4; ++k) corners[m][k] = meshes_[m].sampler->point(p, Vec2(k == 1 || k == 2, k >= 2));
      ranges[m] = {meshes_[m].patch_begin[p], meshes_[m].patch_begin[p + 1]};
    }
    refine({p, 0, 0, 0}, corners, ranges);
  }

 private:
  void refine(const QuadNode& n, const std::vector<std::array<Vec3, 4>>& corners,
              const std::vector<std::array<int, 2>>& ranges) {
    const size_t nm = meshes_.size();
    const double size = 1.0 / (1 << n.level);
    const double u0 = n.i * size, v0 = n.j * size, um = u0 + 0.5 * size, vm = v0 + 0.5 * size;
    const bool can_split = n.level < o_.max_level;
    const bool forced = n.level < o_.min_level;
    // The 5 grid points of level l+1 inside the node: side midpoints M0..M3, then the centre.
    const std::array<Vec2, 5> mid_uv = {Vec2(um, v0), Vec2(u0 + size, vm), Vec2(um, v0 + size), Vec2(u0, vm), Vec2(um, vm)};
    std::vector<std::array<Vec3, 5>> mids(nm);
    for (size_t m = 0; m < nm; ++m)
      for (int k = 0; k < 5; ++k) mids[m][k] = meshes_[m].sampler->point(n.patch, mid_uv[k]);

    bool split = forced && can_split;
    if (!forced) {
      ++stats_.evaluated_nodes;
      const bool d02 = node_diagonal02(t_, n);
      double error = 0;
      const double bound = o_.criterion == AdaptiveCriterion::Size ? o_.max_area : o_.epsilon;
      if (o_.criterion == AdaptiveCriterion::Size) {
        // A_C(q): the node's share of the surface, from its 3 x 3 grid points (8 triangles).
        auto tri = [](const Vec3& a, const Vec3& b, const Vec3& c) { return 0.5 * (b - a).cross(c - a).norm(); };
        for (size_t m = 0; m < nm; ++m) {
          const auto& c = corners[m];
          const auto& x = mids[m];  // M0 (bottom), M1 (right), M2 (top), M3 (left), centre
          const double area = tri(c[0], x[0], x[4]) + tri(c[0], x[4], x[3]) + tri(x[0], c[1], x[1]) +
                              tri(x[0], x[1], x[4]) + tri(x[4], x[1], c[2]) + tri(x[4], c[2], x[2]) +
                              tri(x[3], x[4], x[2]) + tri(x[3], x[2], c[3]);
          error = std::max(error, area * meshes_[m].inv_area);
        }
      } else {
        for (size_t m = 0; m < nm; ++m) {
          const auto& c = corners[m];
          // The node's triangles: (C0,C1,C2), (C0,C2,C3) or (C0,C1,C3), (C1,C2,C3).
          auto dist2 = [&](const Vec3& x) {
            if (d02) return std::min(point_triangle_distance2(x, c[0], c[1], c[2]), point_triangle_distance2(x, c[0], c[2], c[3]));
            return std::min(point_triangle_distance2(x, c[0], c[1], c[3]), point_triangle_distance2(x, c[1], c[2], c[3]));
          };
          double worst = 0;
          for (int s = ranges[m][0]; s < ranges[m][1]; ++s) worst = std::max(worst, dist2(meshes_[m].samples[s].x));
          for (int k = 0; k < 5; ++k) worst = std::max(worst, dist2(mids[m][k]));
          error = std::max(error, std::sqrt(worst) * meshes_[m].inv_diagonal);
        }
      }
      if (error > bound && can_split) split = true;
      if (!split) {
        stats_.max_leaf_error = std::max(stats_.max_leaf_error, error);
        if (error > bound) {
          ++stats_.unresolved_leaves;
          stats_.max_unresolved_error = std::max(stats_.max_unresolved_error, error);
        }
      }
    }
    if (!split) return;
    forest_.split(n);
    ++stats_.error_splits;

    // Children (2i+a, 2j+b), ab = 00, 10, 01, 11, with their corners and sample ranges.
    std::array<std::vector<std::array<Vec3, 4>>, 4> child_corners;
    std::array<std::vector<std::array<int, 2>>, 4> child_ranges;
    for (int c = 0; c < 4; ++c) {
      child_corners[c].resize(nm);
      child_ranges[c].resize(nm);
    }
    for (size_t m = 0; m < nm; ++m) {
      const auto& c = corners[m];
      const auto& md = mids[m];
      child_corners[0][m] = {c[0], md[0], md[4], md[3]};
      child_corners[1][m] = {md[0], c[1], md[1], md[4]};
      child_corners[2][m] = {md[3], md[4], md[2], c[3]};
      child_corners[3][m] = {md[4], md[1], c[2], md[2]};
      auto& s = meshes_[m].samples;
      const auto b = s.begin() + ranges[m][0], e = s.begin() + ranges[m][1];
      const auto lower = std::partition(b, e, [vm](const Sample& x) { return x.uv.y() < vm; });
      const auto l1 = std::partition(b, lower, [um](const Sample& x) { return x.uv.x() < um; });
      const auto u1 = std::partition(lower, e, [um](const Sample& x) { return x.uv.x() < um; });
      const int ib = ranges[m][0], il = static_cast<int>(lower - s.begin());
      const int i1 = static_cast<int>(l1 - s.begin()), i2 = static_cast<int>(u1 - s.begin());
      child_ranges[0][m] = {ib, i1};
      child_ranges[1][m] = {i1, il};
      child_ranges[2][m] = {il, i2};
      child_ranges[3][m] = {i2, ranges[m][1]};
    }
    for (int c = 0; c < 4; ++c)
      refine({n.patch, n.level + 1, 2 * n.i + (c & 1), 2 * n.j + (c >> 1)}, child_corners[c], child_ranges[c]);
  }

  const BaseTopology& t_;
  std::vector<MeshData>& meshes_;
  const AdaptiveOptions& o_;
  Forest& forest_;
  AdaptiveStats& stats_;
};

}  // namespace

QuadForest balance_forest(const BaseTopology& topology, const std::vector<QuadNode>& split_nodes) {
  int levels = 1;
  for (const auto& n : split_nodes) {
    check_node(topology, n);
    levels = std::max(levels, n.level + 1);
  }
  Forest f(topology, levels);
  for (const auto& n : split_nodes) {
    f.ensure_exists(n);
    f.split(n);
  }
  f.balance();
  return finish(topology, f);
}

SemiRegularConnectivity adaptive_connectivity(const BaseTopology& topology, const QuadForest& forest) {
  const int top = forest.max_level;
  if (top < 0 || top > kMaxAdaptiveLevel)
    throw InvalidInput("remesh: a quadtree of level " + std::to_string(top) + "; at most " +
                       std::to_string(kMaxAdaptiveLevel) + " is supported");
  Forest f(topology, std::max(top, 1));
  for (const auto& n : forest.split) {
    check_node(topology, n);
    f.split(n);
  }
  const UniformNumbering num(topology, top);
  std::vector<std::array<std::int64_t, 3>> faces;
  faces.reserve(2 * forest.leaves.size() + forest.leaves.size() / 2);
  for (const auto& n : forest.leaves) {
    const int s = 1 << (top - n.level), h = s / 2;
    const int i0 = n.i * s, j0 = n.j * s;
    const std::array<std::int64_t, 4> c = {num.vertex(n.patch, i0, j0), num.vertex(n.patch, i0 + s, j0),
                                           num.vertex(n.patch, i0 + s, j0 + s), num.vertex(n.patch, i0, j0 + s)};
    std::array<bool, 4> t{};
    int nt = 0;
    for (int d = 0; d < 4; ++d) nt += (t[d] = f.is_split(f.neighbour(n, d)));
    if (nt == 0) {
      push_cell(faces, c, node_diagonal02(topology, n));
      continue;
    }
    // h >= 1 here: a split neighbour has children of level n.level + 1 <= top.
    const std::array<std::int64_t, 4> m = {num.vertex(n.patch, i0 + h, j0), num.vertex(n.patch, i0 + s, j0 + h),
                                           num.vertex(n.patch, i0 + h, j0 + s), num.vertex(n.patch, i0, j0 + h)};
    if (nt == 1) {
      const int d = static_cast<int>(std::find(t.begin(), t.end(), true) - t.begin());
      faces.push_back({c[d], m[d], c[(d + 3) % 4]});
      faces.push_back({m[d], c[(d + 1) % 4], c[(d + 2) % 4]});
      faces.push_back({m[d], c[(d + 2) % 4], c[(d + 3) % 4]});
      continue;
    }
    const std::int64_t centre = num.vertex(n.patch, i0 + h, j0 + h);
    std::vector<std::int64_t> ring;
    for (int d = 0; d < 4; ++d) {
      ring.push_back(c[d]);
      if (t[d]) ring.push_back(m[d]);
    }
    for (size_t r = 0; r < ring.size(); ++r) faces.push_back({centre, ring[r], ring[(r + 1) % ring.size()]});
  }

  return compact_connectivity(topology, num, faces, "the adaptive remesh");
}

AdaptiveRemesh remesh_adaptive(const std::vector<const dissect::Chart*>& charts, const AdaptiveOptions& options,
                               const Context& context) {
  if (options.criterion == AdaptiveCriterion::Size) {
    if (!(options.max_area > 0) || !std::isfinite(options.max_area))
      throw InvalidInput("remesh: the even remesh's area bound must be a positive share of the surface, got " +
                         std::to_string(options.max_area));
  } else if (!(options.epsilon > 0) || !std::isfinite(options.epsilon))
    throw InvalidInput("remesh: epsilon must be a positive number (a fraction of the bounding-box diagonal, e.g. "
                       "0.0025), got " + std::to_string(options.epsilon));
  if (options.max_level < 0 || options.max_level > kMaxAdaptiveLevel)
    throw InvalidInput("remesh: max level " + std::to_string(options.max_level) + " is out of range; expected 0.." +
                       std::to_string(kMaxAdaptiveLevel));
  if (options.min_level < 0 || options.min_level > options.max_level)
    throw InvalidInput("remesh: min level " + std::to_string(options.min_level) + " is out of range; expected 0.." +
                       std::to_string(options.max_level) + " (the max level)");

  const std::vector<ChartSampler> samplers = set_samplers(charts, context);
  const BaseTopology& topology = samplers[0].topology();
  std::vector<MeshData> meshes;
  for (const auto& s : samplers) meshes.push_back(gather_samples(s, options.criterion == AdaptiveCriterion::Error));

  AdaptiveRemesh out;
  Forest forest(topology, std::max(options.max_level, 1));
  Refiner refiner(topology, meshes, options, forest, out.stats);
  const int np = topology.num_patches();
  for (int p = 0; p < np; ++p) {
    context.check_cancel();
    context.report("remesh", 0.8 * p / np);
    refiner.refine_patch(p);
  }
  out.stats.balance_splits = forest.balance();
  out.forest = finish(topology, forest);
  out.stats.leaves_per_level.assign(out.forest.max_level + 1, 0);
  for (const auto& n : out.forest.leaves) ++out.stats.leaves_per_level[n.level];

  out.remesh.connectivity = adaptive_connectivity(topology, out.forest);
  for (size_t m = 0; m < samplers.size(); ++m) {
    context.report("remesh", 0.8 + 0.2 * m / samplers.size());
    out.remesh.positions.push_back(sample_positions(samplers[m], out.remesh.connectivity, context));
  }
  if (options.best_angle_diagonals) {
    Forest f(topology, std::max(out.forest.max_level, 1));
    for (const auto& n : out.forest.split) f.split(n);
    choose_leaf_diagonals(topology, out.forest, f, out.remesh.connectivity, out.remesh.positions);
  }
  context.report("remesh", 1.0);
  return out;
}

AdaptiveRemesh remesh_adaptive(const std::vector<dissect::Chart>& charts, const AdaptiveOptions& options,
                               const Context& context) {
  std::vector<const dissect::Chart*> ptrs;
  for (const auto& c : charts) ptrs.push_back(&c);
  return remesh_adaptive(ptrs, options, context);
}

AdaptiveOptions even_options(int level, int patches, double share_sum) {
  if (level < 0 || level > kMaxAdaptiveLevel)
    throw InvalidInput("remesh: even level " + std::to_string(level) + " is out of range; expected 0.." +
                       std::to_string(kMaxAdaptiveLevel));
  if (patches < 1) throw InvalidInput("remesh: " + std::to_string(patches) + " patches; expected at least 1");
  if (!(share_sum >= 1) || !std::isfinite(share_sum))
    throw InvalidInput("remesh: the patches' largest shares of the surface add up to " + std::to_string(share_sum) +
                       "; expected a finite number >= 1");
  AdaptiveOptions o;
  o.criterion = AdaptiveCriterion::Size;
  o.max_area = kEvenAreaFactor * share_sum / (static_cast<double>(patches) * std::ldexp(1.0, 2 * level));
  o.min_level = 0;
  o.max_level = std::min(level + 6, kMaxAdaptiveLevel);
  o.best_angle_diagonals = true;
  return o;
}

AdaptiveRemesh remesh_even(const std::vector<const dissect::Chart*>& charts, int level, const Context& context) {
  if (charts.empty() || charts.front() == nullptr) throw InvalidInput("remesh: no charts to remesh");
  double sum = 0;
  for (double a : patch_area_shares(charts)) sum += a;
  return remesh_adaptive(charts, even_options(level, static_cast<int>(charts.front()->patches.size()), std::max(sum, 1.0)),
                         context);
}

}  // namespace qs::remesh
