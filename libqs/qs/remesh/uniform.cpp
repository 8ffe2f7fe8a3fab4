#include "qs/remesh/uniform.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <string>

#include "qs/core/error.h"
#include "qs/remesh/chart_sampler.h"

namespace qs::remesh {

UniformNumbering::UniformNumbering(const BaseTopology& topology, int level) : topology_(&topology), level_(level) {
  if (level < 0 || level > kMaxUniformLevel)
    throw InvalidInput("remesh: level " + std::to_string(level) + " is out of range; expected 0.." +
                       std::to_string(kMaxUniformLevel));
  n_ = 1 << level;
  edge_first_ = topology.num_vertices;
  interior_first_ = edge_first_ + static_cast<std::int64_t>(topology.num_edges()) * (n_ - 1);
}

std::int64_t UniformNumbering::vertex(int patch, int i, int j) const {
  const int n = n_;
  const bool bi = i == 0 || i == n, bj = j == 0 || j == n;
  if (bi && bj) return topology_->quads[patch][j == 0 ? (i == 0 ? 0 : 1) : (i == n ? 2 : 3)];
  if (bi || bj) {
    int k, s;
    if (j == 0) k = 0, s = i;
    else if (i == n) k = 1, s = j;
    else if (j == n) k = 2, s = n - i;
    else k = 3, s = n - j;
    const int off = topology_->side_forward[patch][k] ? s - 1 : n - 1 - s;
    return edge_first_ + static_cast<std::int64_t>(topology_->side_edge[patch][k]) * (n - 1) + off;
  }
  return interior_first_ + (static_cast<std::int64_t>(patch) * (n - 1) + (j - 1)) * (n - 1) + (i - 1);
}

void UniformNumbering::site(std::int64_t id, int& patch, int& i, int& j) const {
  const int n = n_;
  static constexpr int kCornerI[4] = {0, 1, 1, 0}, kCornerJ[4] = {0, 0, 1, 1};
  if (id < edge_first_) {
    const auto [p, k] = topology_->vertex_corner[static_cast<size_t>(id)];
    patch = p, i = kCornerI[k] * n, j = kCornerJ[k] * n;
  } else if (id < interior_first_) {
    const std::int64_t e = (id - edge_first_) / (n - 1);
    const int s = static_cast<int>((id - edge_first_) % (n - 1)) + 1;
    const auto [p, k] = topology_->edge_sides[static_cast<size_t>(e)][0];
    patch = p;
    switch (k) {
      case 0: i = s, j = 0; break;
      case 1: i = n, j = s; break;
      case 2: i = n - s, j = n; break;
      default: i = 0, j = n - s; break;
    }
  } else {
    const std::int64_t r = id - interior_first_, per = static_cast<std::int64_t>(n - 1) * (n - 1);
    patch = static_cast<int>(r / per);
    j = static_cast<int>((r % per) / (n - 1)) + 1;
    i = static_cast<int>(r % (n - 1)) + 1;
  }
}

SemiRegularConnectivity compact_connectivity(const BaseTopology& topology, const UniformNumbering& num,
                                             const std::vector<std::array<std::int64_t, 3>>& faces,
                                             const std::string& what, int* used_bits) {
  std::vector<std::int64_t> ids;
  ids.reserve(3 * faces.size());
  for (const auto& tri : faces) ids.insert(ids.end(), tri.begin(), tri.end());
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  if (ids.size() > static_cast<size_t>(INT_MAX) || faces.size() > static_cast<size_t>(INT_MAX))
    throw InvalidInput("remesh: " + what + " would have " + std::to_string(ids.size()) + " vertices and " +
                       std::to_string(faces.size()) + " faces; at most 2^31 - 1 each are supported");
  SemiRegularConnectivity out;
  out.num_base_vertices = topology.num_vertices;
  out.num_base_edges = topology.num_edges();
  out.num_patches = topology.num_patches();
  out.level = num.level();
  auto index = [&](std::int64_t id) {
    return static_cast<int>(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin());
  };
  out.faces.reserve(faces.size());
  for (const auto& tri : faces) out.faces.push_back({index(tri[0]), index(tri[1]), index(tri[2])});
  out.vertex_patch.resize(ids.size());
  out.vertex_uv.resize(ids.size());
  const double inv = 1.0 / num.cells();
  int bits = 0;
  for (size_t v = 0; v < ids.size(); ++v) {
    int p, i, j;
    num.site(ids[v], p, i, j);
    out.vertex_patch[v] = p;
    out.vertex_uv[v] = Vec2(i * inv, j * inv);
    bits |= i | j;
  }
  if (used_bits) *used_bits = bits;
  return out;
}

SemiRegularConnectivity uniform_connectivity(const BaseTopology& topology, int level, const UniformOptions& options) {
  const UniformNumbering num(topology, level);
  const int n = num.cells(), np = topology.num_patches();
  const std::int64_t nv = num.num_vertices(), nf = 2 * static_cast<std::int64_t>(np) * n * n;
  if (nv > INT_MAX || nf > INT_MAX)
    throw InvalidInput("remesh: level " + std::to_string(level) + " of " + std::to_string(np) + " patches would make " +
                       std::to_string(nv) + " vertices and " + std::to_string(nf) +
                       " faces; at most 2147483647 of each are supported");
  SemiRegularConnectivity c;
  c.num_base_vertices = topology.num_vertices;
  c.num_base_edges = topology.num_edges();
  c.num_patches = np;
  c.level = level;
  c.vertex_patch.resize(nv);
  c.vertex_uv.resize(nv);
  const double inv = 1.0 / n;
  for (std::int64_t v = 0; v < nv; ++v) {
    int p, i, j;
    num.site(v, p, i, j);
    c.vertex_patch[v] = p;
    c.vertex_uv[v] = Vec2(i * inv, j * inv);
  }
  c.faces.reserve(nf);
  if (options.quads) c.quads.reserve(nf / 2);
  std::vector<int> row0(n + 1), row1(n + 1);
  for (int p = 0; p < np; ++p) {
    for (int i = 0; i <= n; ++i) row1[i] = static_cast<int>(num.vertex(p, i, 0));
    for (int j = 0; j < n; ++j) {
      row0.swap(row1);
      for (int i = 0; i <= n; ++i) row1[i] = static_cast<int>(num.vertex(p, i, j + 1));
      for (int i = 0; i < n; ++i) {
        const int v00 = row0[i], v10 = row0[i + 1], v11 = row1[i + 1], v01 = row1[i];
        const bool diag02 = level == 0 ? bool(topology.level0_diagonal02[p]) : ((2 * i < n) == (2 * j < n));
        if (diag02) {
          c.faces.push_back({v00, v10, v11});
          c.faces.push_back({v00, v11, v01});
        } else {
          c.faces.push_back({v00, v10, v01});
          c.faces.push_back({v10, v11, v01});
        }
        if (options.quads) c.quads.push_back({v00, v10, v11, v01});
      }
    }
  }
  return c;
}

SemiRegularConnectivity uniform_connectivity(const std::vector<dissect::PatchInfo>& patches, int level,
                                             const UniformOptions& options) {
  return uniform_connectivity(build_base_topology(patches), level, options);
}

namespace {

// sample_positions() for a uniform connectivity: corners and sides point by point, each patch's
// interior as one grid (ChartSampler::locate_grid: no search per point).
std::vector<Vec3> uniform_positions(const ChartSampler& sampler, const SemiRegularConnectivity& c,
                                    const Context& context) {
  const int n = 1 << c.level, m = n - 1;
  const int interior_first = c.num_base_vertices + c.num_base_edges * m;
  std::vector<Vec3> positions(c.num_vertices());
  for (int v = 0; v < interior_first; ++v) positions[v] = sampler.point(c.vertex_patch[v], c.vertex_uv[v]);
  for (int p = 0; p < c.num_patches && m > 0; ++p) {
    if ((p & 15) == 15) context.check_cancel();
    const auto locs = sampler.locate_grid(p, m, 1.0 / n, 1.0 / n);
    Vec3* out = positions.data() + interior_first + static_cast<size_t>(p) * m * m;
    for (size_t k = 0; k < locs.size(); ++k) out[k] = sampler.position(locs[k]);
  }
  return positions;
}

/// sin of the smallest angle of triangle (a, b, c): the angle opposite the shortest edge (at most
/// 60 degrees, where sin is increasing). 0 for a degenerate triangle.
double sin_smallest_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, bc = c - b, ca = a - c;
  const double lab = ab.squaredNorm(), lbc = bc.squaredNorm(), lca = ca.squaredNorm();
  const double twice_area = ab.cross(ca).norm();
  // The smallest angle is at the vertex opposite the shortest edge; its sides are the other two.
  double denom2;
  if (lab <= lbc && lab <= lca) denom2 = lbc * lca;       // opposite ab: at c
  else if (lbc <= lca) denom2 = lab * lca;                // opposite bc: at a
  else denom2 = lab * lbc;                                // opposite ca: at b
  return denom2 > 0 ? twice_area / std::sqrt(denom2) : 0.0;
}

/// DiagonalRule::BestAngle: re-cuts the cells of a uniform connectivity (faces 2k, 2k+1 are cell
/// k, patch by patch, row by row, as uniform_connectivity emits them).
void choose_best_angle_diagonals(const BaseTopology& topology, SemiRegularConnectivity& c,
                                 const std::vector<std::vector<Vec3>>& positions) {
  const int n = 1 << c.level;
  if (c.level < 1) return;
  for (int p = 0; p < c.num_patches; ++p)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        if ((i == 0 || i == n - 1) && (j == 0 || j == n - 1)) {
          // A corner cell: its other diagonal joins the two side samples next to the patch
          // corner, which another patch joins too only when the corner has valence 2 (the two
          // patches share both sides). Keep the pattern's diagonal there.
          const int k = j == 0 ? (i == 0 ? 0 : 1) : (i == 0 ? 3 : 2);
          if (n == 1 || topology.valence[topology.quads[p][k]] < 3) continue;
          if (n == 2) {
            // Level 1: every cell touches two corners' sides; require all four corners free.
            bool free = true;
            for (int q = 0; q < 4; ++q) free = free && topology.valence[topology.quads[p][q]] >= 3;
            if (!free) continue;
          }
        }
        const size_t k = (static_cast<size_t>(p) * n + j) * n + i;
        Tri& f0 = c.faces[2 * k];
        Tri& f1 = c.faces[2 * k + 1];
        const bool diag02 = (2 * i < n) == (2 * j < n);
        recut_cell_best_angle(f0, f1, diag02, positions);
      }
}

/// Cells per side of the probe grid that measures each patch's map (UniformOptions::relax).
constexpr int kProbeCells = 16;
/// Largest |log| of a cell's sample density against the regular grid's (factor 4 either way).
constexpr double kMaxLogDensity = 1.3862943611198906;

/// UniformOptions::relax: the side samples of every base edge, N + 1 fractions in the edge's
/// (owner's) direction, first 0, last 1, strictly increasing.
///
/// Each patch's map is probed on a kProbeCells^2 grid in every mesh: r = log(Sv / Su), Su and Sv
/// the 3D lengths of a probe cell's u and v sides (mean of the two opposite ones). A separable
/// reparameterization u = U(s), v = V(t) makes the cells square when log U' - log V' = r; its
/// least-squares fit is log U' = mean over v of r, log V' = -(mean over u of r) (each up to a
/// constant fixed by U(1) = V(1) = 1). Their inverses (samples per unit of s, t) are the patch's
/// preferred sample densities along u and v (mean of r over the meshes, times relax, clamped to kMaxLogDensity). A base edge's
/// density is the mean of the preferences of its two patches along it, so that both patches
/// sample the edge identically.
std::vector<std::vector<double>> relaxed_edge_samples(const std::vector<const ChartSampler*>& samplers, int n,
                                                      double relax) {
  const BaseTopology& t = samplers[0]->topology();
  const int np = t.num_patches(), K = kProbeCells;
  // log density per patch along u (du) and along v (dv), K cells each.
  std::vector<std::vector<double>> du(np, std::vector<double>(K, 0.0)), dv(np, std::vector<double>(K, 0.0));
  std::vector<double> r(static_cast<size_t>(K) * K);
  for (int p = 0; p < np; ++p) {
    int counted = 0;
    std::vector<double> fu(K, 0.0), fv(K, 0.0);
    for (const ChartSampler* s : samplers) {
      const auto locs = s->locate_grid(p, K + 1, 0.0, 1.0 / K);
      std::vector<Vec3> x(locs.size());
      for (size_t k = 0; k < locs.size(); ++k) x[k] = s->position(locs[k]);
      auto at = [&](int i, int j) -> const Vec3& { return x[static_cast<size_t>(j) * (K + 1) + i]; };
      bool ok = true;
      for (int j = 0; j < K && ok; ++j)
        for (int i = 0; i < K; ++i) {
          const double su = 0.5 * ((at(i + 1, j) - at(i, j)).norm() + (at(i + 1, j + 1) - at(i, j + 1)).norm());
          const double sv = 0.5 * ((at(i, j + 1) - at(i, j)).norm() + (at(i + 1, j + 1) - at(i + 1, j)).norm());
          if (!(su > 0) || !(sv > 0) || !std::isfinite(su) || !std::isfinite(sv)) { ok = false; break; }
          r[static_cast<size_t>(j) * K + i] = std::log(sv / su);
        }
      if (!ok) continue;  // a degenerate probe cell: this mesh has no say for this patch
      ++counted;
      for (int j = 0; j < K; ++j)
        for (int i = 0; i < K; ++i) {
          const double x_ = r[static_cast<size_t>(j) * K + i] / K;
          fu[i] -= x_, fv[j] += x_;  // sample density = 1 / spacing
        }
    }
    if (counted == 0) continue;
    for (auto* f : {&fu, &fv}) {
      double mean = 0;
      for (double x_ : *f) mean += x_ / counted / K;
      for (double& x_ : *f) x_ = std::clamp(relax * (x_ / counted - mean), -kMaxLogDensity, kMaxLogDensity);
    }
    du[p] = fu, dv[p] = fv;
  }
  // Log density along side k of patch p, in the side's own direction (corner k -> k + 1).
  auto side_density = [&](int p, int k, int cell) {
    switch (k) {
      case 0: return du[p][cell];
      case 1: return dv[p][cell];
      case 2: return du[p][K - 1 - cell];
      default: return dv[p][K - 1 - cell];
    }
  };
  std::vector<std::vector<double>> out(t.num_edges(), std::vector<double>(n + 1));
  std::vector<double> cdf(K + 1);
  for (int e = 0; e < t.num_edges(); ++e) {
    const PatchSide owner = t.edge_sides[e][0], twin = t.edge_sides[e][1];
    cdf[0] = 0;
    for (int cell = 0; cell < K; ++cell)
      cdf[cell + 1] = cdf[cell] + std::exp(0.5 * (side_density(owner.patch, owner.side, cell) +
                                                 side_density(twin.patch, twin.side, K - 1 - cell)));
    const double total = cdf[K];
    auto& x = out[e];
    x[0] = 0.0, x[n] = 1.0;
    int cell = 0;
    for (int q = 1; q < n; ++q) {
      const double target = total * q / n;
      while (cell < K - 1 && cdf[cell + 1] <= target) ++cell;
      const double w = (target - cdf[cell]) / (cdf[cell + 1] - cdf[cell]);
      x[q] = std::clamp((cell + w) / K, 0.0, 1.0);
    }
  }
  return out;
}

/// Rewrites the vertex_uv of a uniform connectivity by UniformOptions::relax (see uniform.h).
void relax_grid(const std::vector<const ChartSampler*>& samplers, SemiRegularConnectivity& c, double relax) {
  const int n = 1 << c.level;
  if (n < 2) return;
  const BaseTopology& t = samplers[0]->topology();
  const auto edge = relaxed_edge_samples(samplers, n, relax);
  // sigma(p, k, q): sample q (0..N) of side k of patch p, as a fraction along the side's own
  // direction (corner k -> corner k + 1).
  auto sigma = [&](int p, int k, int q) {
    const auto& x = edge[t.side_edge[p][k]];
    return t.side_forward[p][k] ? x[q] : 1.0 - x[n - q];
  };
  const UniformNumbering num(t, c.level);
  std::vector<double> a(n + 1), b(n + 1), cc(n + 1), d(n + 1);
  for (int p = 0; p < c.num_patches; ++p) {
    for (int q = 0; q <= n; ++q) {
      a[q] = sigma(p, 0, q);             // bottom (v = 0): u
      b[q] = sigma(p, 1, q);             // right (u = 1): v
      cc[q] = 1.0 - sigma(p, 2, n - q);  // top (v = 1): u, side 2 runs u from 1 to 0
      d[q] = 1.0 - sigma(p, 3, n - q);   // left (u = 0): v, side 3 runs v from 1 to 0
    }
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const std::int64_t v = num.vertex(p, i, j);
        if (c.vertex_patch[v] != p) continue;  // recorded by a lower patch (its owner)
        const bool bi = i == 0 || i == n, bj = j == 0 || j == n;
        if (bi && bj) continue;  // corners stay exact
        Vec2 uv;
        if (j == 0) uv = Vec2(a[i], 0.0);
        else if (j == n) uv = Vec2(cc[i], 1.0);
        else if (i == 0) uv = Vec2(0.0, d[j]);
        else if (i == n) uv = Vec2(1.0, b[j]);
        else {
          const double wu = static_cast<double>(i) / n, wv = static_cast<double>(j) / n;
          uv = Vec2((1 - wv) * a[i] + wv * cc[i], (1 - wu) * d[j] + wu * b[j]);
        }
        c.vertex_uv[v] = uv;
      }
  }
}

void check_relax(double relax) {
  if (!(relax >= 0 && relax <= kMaxGridRelax))
    throw InvalidInput("remesh: grid relaxation " + std::to_string(relax) + " is out of range; expected 0.." +
                       std::to_string(kMaxGridRelax));
}

}  // namespace

void recut_cell_best_angle(Tri& f0, Tri& f1, bool diag02, const std::vector<std::vector<Vec3>>& positions) {
  // Recover the cell's corners from its two faces.
  const int v00 = f0[0], v10 = f0[1];
  const int v11 = diag02 ? f0[2] : f1[1], v01 = diag02 ? f1[2] : f0[2];
  double keep = 1e300, other = 1e300;
  for (const auto& x : positions) {
    const Vec3 &a = x[v00], &b = x[v10], &cc = x[v11], &d = x[v01];
    const double q02 = std::min(sin_smallest_angle(a, b, cc), sin_smallest_angle(a, cc, d));
    const double q13 = std::min(sin_smallest_angle(a, b, d), sin_smallest_angle(b, cc, d));
    keep = std::min(keep, diag02 ? q02 : q13);
    other = std::min(other, diag02 ? q13 : q02);
  }
  if (!(other > keep)) return;
  if (diag02) f0 = {v00, v10, v01}, f1 = {v10, v11, v01};
  else f0 = {v00, v10, v11}, f1 = {v00, v11, v01};
}

SemiRegular remesh_uniform(const dissect::Chart& chart, int level, const UniformOptions& options,
                           const Context& context) {
  check_relax(options.relax);
  const ChartSampler sampler(chart, context);
  SemiRegular out;
  out.connectivity = uniform_connectivity(sampler.topology(), level, options);
  if (options.relax > 0) {
    relax_grid({&sampler}, out.connectivity, options.relax);
    out.positions = sample_positions(sampler, out.connectivity, context);
  } else {
    out.positions = uniform_positions(sampler, out.connectivity, context);
  }
  if (options.diagonals == DiagonalRule::BestAngle) {
    std::vector<std::vector<Vec3>> one{std::move(out.positions)};
    choose_best_angle_diagonals(sampler.topology(), out.connectivity, one);
    out.positions = std::move(one[0]);
  }
  return out;
}

std::vector<ChartSampler> set_samplers(const std::vector<const dissect::Chart*>& charts, const Context& context) {
  if (charts.empty()) throw InvalidInput("remesh: no charts given");
  std::vector<ChartSampler> samplers;
  samplers.reserve(charts.size());
  for (const auto* c : charts) samplers.emplace_back(*c, context);
  const auto& first = samplers[0].chart().patches;
  const auto& t0 = samplers[0].topology();
  for (size_t m = 1; m < samplers.size(); ++m) {
    const auto& patches = samplers[m].chart().patches;
    const std::string which = "remesh: chart " + std::to_string(m) + " does not match chart 0: ";
    if (patches.size() != first.size())
      throw InvalidInput(which + std::to_string(patches.size()) + " patches instead of " +
                         std::to_string(first.size()) + "; remesh charts of one common dissection (qs-dissect on the whole set)");
    for (size_t p = 0; p < patches.size(); ++p) {
      if (patches[p].name != first[p].name)
        throw InvalidInput(which + "patch " + std::to_string(p) + " is '" + patches[p].name + "' instead of '" +
                           first[p].name + "'");
      if (samplers[m].topology().quads[p] != t0.quads[p])
        throw InvalidInput(which + "the corners of patch " + std::to_string(p) + " ('" + first[p].name +
                           "') join other base vertices; the base domains differ");
    }
  }
  return samplers;
}

SemiRegularSet remesh_uniform(const std::vector<const dissect::Chart*>& charts, int level,
                              const UniformOptions& options, const Context& context) {
  check_relax(options.relax);
  const std::vector<ChartSampler> samplers = set_samplers(charts, context);
  SemiRegularSet out;
  out.connectivity = uniform_connectivity(samplers[0].topology(), level, options);
  if (options.relax > 0) {
    std::vector<const ChartSampler*> ptrs;
    for (const auto& s : samplers) ptrs.push_back(&s);
    relax_grid(ptrs, out.connectivity, options.relax);
  }
  for (size_t m = 0; m < samplers.size(); ++m) {
    context.report("remesh", static_cast<double>(m) / samplers.size());
    out.positions.push_back(options.relax > 0 ? sample_positions(samplers[m], out.connectivity, context)
                                              : uniform_positions(samplers[m], out.connectivity, context));
  }
  if (options.diagonals == DiagonalRule::BestAngle)
    choose_best_angle_diagonals(samplers[0].topology(), out.connectivity, out.positions);
  context.report("remesh", 1.0);
  return out;
}

SemiRegularSet remesh_uniform(const std::vector<dissect::Chart>& charts, int level, const UniformOptions& options,
                              const Context& context) {
  std::vector<const dissect::Chart*> ptrs;
  for (const auto& c : charts) ptrs.push_back(&c);
  return remesh_uniform(ptrs, level, options, context);
}

}  // namespace qs::remesh
