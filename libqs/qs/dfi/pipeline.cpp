#include "qs/dfi/pipeline.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dfi/topology.h"
#include "qs/dfi/transport.h"
#include "qs/metro/metro.h"

namespace qs::dfi {
namespace {

constexpr size_t kSpeck = 8;      // inside islands of at most this many samples are dropped,
constexpr double kSpeckShare = 0.002;  // or of at most this share of the frame's inside samples
// Jacobi steps on each frame's bone displacement on a 75-cell bone grid (a 150-cell morph),
// scaled with the square of the cells for other grids so that the smoothing radius stays the same
// in space (measured on horse -> camel at 150: 4 leave handles where the warp folds, 64 thin the
// legs until they detach).
constexpr double kBoneSmoothing = 32;
Displacement frame_bone_warp(const std::vector<Bone>& bones, const Grid& geometry, double s, int threads);

// Volume centroid of a closed outward mesh (signed tetrahedra about the bounding-box centre).
Vec3 volume_centroid(const TriMesh& m, double& volume) {
  const Box3 box = bounding_box(m.positions);
  const Vec3 o = 0.5 * (box.min + box.max);
  Vec3 c = Vec3::Zero();
  double v = 0;
  for (const Tri& t : m.faces) {
    const Vec3 a = m.positions[t[0]] - o, b = m.positions[t[1]] - o, d = m.positions[t[2]] - o;
    const double vol = a.dot(b.cross(d)) / 6.0;
    v += vol;
    c += vol * (a + b + d) / 4.0;
  }
  volume = v;
  return v != 0 ? Vec3(o + c / v) : o;
}

// Principal axes of inertia (columns, ascending moments), a proper rotation.
Eigen::Matrix3d principal_frame(const TriMesh& m, const Vec3& c) {
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (const Tri& t : m.faces) {
    const Vec3 a = m.positions[t[0]] - c, b = m.positions[t[1]] - c, d = m.positions[t[2]] - c;
    const double vol = a.dot(b.cross(d)) / 6.0;
    const Vec3 sum = a + b + d;
    second += vol / 20.0 * (a * a.transpose() + b * b.transpose() + d * d.transpose() + sum * sum.transpose());
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(second);
  Eigen::Matrix3d e = eig.eigenvectors();
  if (e.determinant() < 0) e.col(2) = -e.col(2);
  return e;
}

// The 24 rotations that map the coordinate axes onto themselves, in a fixed order.
std::vector<Eigen::Matrix3d> cube_rotations() {
  std::vector<Eigen::Matrix3d> out;
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& p : perms)
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
      for (int row = 0; row < 3; ++row) r(row, p[row]) = (signs >> row) & 1 ? -1.0 : 1.0;
      if (r.determinant() > 0) out.push_back(r);
    }
  return out;
}

Eigen::Matrix3d best_rotation(const TriMesh& source, const Vec3& c0, const TriMesh& target, const Vec3& c1,
                              double scale) {
  const Eigen::Matrix3d e0 = principal_frame(source, c0), e1 = principal_frame(target, c1);
  const metro::SurfaceDistance surface(source, "source");
  const int stride = std::max(1, target.num_vertices() / 2000);
  double best = std::numeric_limits<double>::infinity();
  Eigen::Matrix3d best_r = Eigen::Matrix3d::Identity();
  for (const Eigen::Matrix3d& g : cube_rotations()) {
    const Eigen::Matrix3d r = e0 * g * e1.transpose();
    double sum = 0;
    for (int v = 0; v < target.num_vertices(); v += stride)
      sum += surface.distance(scale * (r * (target.positions[v] - c1)) + c0);
    if (sum < best) {
      best = sum;
      best_r = r;
    }
  }
  return best_r;
}

// Distance from p to a branch's polyline.
double branch_distance(const Skeleton& s, const Branch& b, const Vec3& p) {
  double best = (s.nodes[b.nodes[0]] - p).norm();
  for (size_t k = 1; k < b.nodes.size(); ++k) {
    const Vec3 a = s.nodes[b.nodes[k - 1]], c = s.nodes[b.nodes[k]];
    const Vec3 ac = c - a;
    const double l2 = ac.squaredNorm();
    const double u = l2 > 0 ? std::clamp((p - a).dot(ac) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + u * ac - p).norm());
  }
  return best;
}

// Part label per voxel: the matched branch pair whose branch (on this side) is nearest.
std::vector<int> part_labels(const VoxelSet& v, const Skeleton& s, const std::vector<Branch>& branches,
                             const std::vector<BranchPair>& pairs, bool source_side) {
  std::vector<int> label(v.sample.size(), 0);
  if (pairs.empty()) return label;
  for (size_t i = 0; i < v.sample.size(); ++i) {
    const Vec3 p = v.position(static_cast<int>(i));
    double best = std::numeric_limits<double>::infinity();
    for (size_t q = 0; q < pairs.size(); ++q) {
      const Branch& b = branches[source_side ? pairs[q].source : pairs[q].target];
      const double d = branch_distance(s, b, p);
      if (d < best) {
        best = d;
        label[i] = static_cast<int>(q);
      }
    }
  }
  return label;
}

// Skeletons of both shapes (each computed at unit size, then placed into morph space by
// `source_place` / `target_place`), pruned, and their branches.
void build_skeletons(PreparedMorph& m, const TriMesh& source, const Similarity& source_place, const TriMesh& target,
                     const Similarity& target_place, const MorphOptions& o, const Context& ctx) {
  ctx.report("skeletons", 0.0);
  const double diagonal = bounding_box(source.positions).diagonal() * source_place.scale;
  m.source_skeleton = curve_skeleton(source);
  m.target_skeleton = curve_skeleton(target);
  for (Vec3& p : m.source_skeleton.nodes) p = source_place.apply(p);
  for (Vec3& p : m.target_skeleton.nodes) p = target_place.apply(p);
  prune_skeleton(m.source_skeleton, o.prune_fraction * diagonal);
  prune_skeleton(m.target_skeleton, o.prune_fraction * diagonal);
  m.source_branches = skeleton_branches(m.source_skeleton);
  m.target_branches = skeleton_branches(m.target_skeleton);
  ctx.report("skeletons", 1.0);
}

void check_correspondence_options(const MorphOptions& o) {
  if (o.anchors_per_branch < 0 || o.bone_segments < 0 || o.emd_voxels < 50 || !(o.position_weight >= 0) || !(o.prune_fraction >= 0))
    throw InvalidInput("correspondence options out of range: anchors_per_branch >= 0, bone_segments >= 0, emd_voxels >= 50, "
                       "position_weight >= 0, prune_fraction >= 0");
}

// The backward warps of frame t (frame space -> source, frame space -> target) on `geometry`.
std::array<Displacement, 2> arap_backward(const PreparedMorph& m, double t, const Grid& geometry, int threads) {
  const std::vector<Vec3> p = arap_positions(m.arap, t);
  return {thin_plate_displacement(fit_thin_plate(p, m.arap.source, m.arap_lambda), geometry, threads),
          thin_plate_displacement(fit_thin_plate(p, m.arap.target, m.arap_lambda), geometry, threads)};
}

// Centre pairs from the dense correspondence (source voxels with their partners' mean, target
// voxels likewise, sampled farthest-first on their own side) and the anchors; the thin-plate
// smoothing raised (x10 from 1e-4) until the backward warps at t = 1/4, 1/2, 3/4 do not fold.
void build_arap_warp(PreparedMorph& m, const VoxelSet& v0, const std::vector<Vec3>& dest0, const VoxelSet& v1,
                     const std::vector<Vec3>& dest1, const Box3& box, const MorphOptions& o) {
  std::vector<Vec3> xs, ys;
  for (const AnchorPair& a : m.anchors) xs.push_back(a.source), ys.push_back(a.target);
  const int each = std::max(4, (o.arap_centres - static_cast<int>(xs.size())) / 2);
  std::vector<Vec3> p0(v0.sample.size()), p1(v1.sample.size());
  for (size_t i = 0; i < p0.size(); ++i) p0[i] = v0.position(static_cast<int>(i));
  for (size_t j = 0; j < p1.size(); ++j) p1[j] = v1.position(static_cast<int>(j));
  for (int i : farthest_points(p0, each)) xs.push_back(p0[i]), ys.push_back(dest0[i]);
  for (int j : farthest_points(p1, each)) xs.push_back(dest1[j]), ys.push_back(p1[j]);
  if (xs.size() < 8) return;
  m.arap = build_arap(xs, ys);
  const Grid check = grid_over(box, std::max(12, o.grid / 5), 1);
  for (m.arap_lambda = 1e-4;; m.arap_lambda *= 10) {
    m.arap_min_det = std::numeric_limits<double>::infinity();
    for (double t : {0.25, 0.5, 0.75})
      for (const Displacement& d : arap_backward(m, t, check, o.sdf.threads)) m.arap_min_det = std::min(m.arap_min_det, min_jacobian(d));
    if (m.arap_min_det > 0.05 || m.arap_lambda >= 1) break;
  }
  m.bone_grid = grid_over(box, std::max(16, o.grid / 2), 1);
}

void build_correspondence(PreparedMorph& m, const TriMesh& source, const MorphOptions& o, const Context& ctx) {
  m.warp = true;
  const double diagonal = bounding_box(source.positions).diagonal();
  if (o.centre_skeletons) {
    m.source_centring = centre_skeleton(m.source_skeleton, m.source_sdf);
    m.target_centring = centre_skeleton(m.target_skeleton, m.target_sdf);
    m.source_branches = skeleton_branches(m.source_skeleton);
    m.target_branches = skeleton_branches(m.target_skeleton);
  }
  std::vector<NodePair> forced;
  for (const auto& lm : o.landmarks)
    forced.push_back({nearest_node(m.source_skeleton, m.source_to_morph.apply(lm.source)),
                      nearest_node(m.target_skeleton, m.target_to_morph.apply(lm.target)), true, lm.name});
  MatchOptions match;
  match.voting = o.voting;
  m.matching = match_skeletons(m.source_skeleton, m.source_branches, m.target_skeleton, m.target_branches, forced,
                               diagonal, match);
  std::vector<AnchorPair> anchors = sample_anchors(m.source_skeleton, m.source_branches, m.target_skeleton,
                                                   m.target_branches, m.matching, o.anchors_per_branch);
  // The coarse grid: about emd_voxels interior voxels for the larger shape.
  const Box3 box{m.source_sdf.origin, m.source_sdf.origin + m.source_sdf.spacing * Vec3(m.source_sdf.dims[0] - 1,
                                                                                      m.source_sdf.dims[1] - 1,
                                                                                      m.source_sdf.dims[2] - 1)};
  auto coarse = [&](int cells) { return grid_over(box, cells, 1); };
  int cells = 40;
  VoxelSet v0 = interior_voxels(m.source_sdf, coarse(cells)), v1 = interior_voxels(m.target_sdf, coarse(cells));
  const double most = static_cast<double>(std::max(v0.sample.size(), v1.sample.size()));
  if (most > 0) {
    cells = std::clamp(static_cast<int>(cells * std::cbrt(o.emd_voxels / most)), 8, 200);
    v0 = interior_voxels(m.source_sdf, coarse(cells));
    v1 = interior_voxels(m.target_sdf, coarse(cells));
  }
  if (v0.sample.empty() || v1.sample.empty())
    throw InvalidInput("a shape has no interior voxel on the correspondence grid (" + std::to_string(cells) +
                       " cells): it is too thin for it, or too small beside the other (--align similarity scales "
                       "the target to the source; --no-warp blends without the correspondence)");
  m.emd_cells = cells;
  m.source_voxels = static_cast<int>(v0.sample.size());
  m.target_voxels = static_cast<int>(v1.sample.size());
  // Anchor voxels, distinct on both sides; without any, the volume centroids.
  if (anchors.empty()) anchors.push_back({m.source_centroid, m.source_centroid});
  std::vector<int> a0, a1;
  std::vector<char> taken0(v0.sample.size(), 0), taken1(v1.sample.size(), 0);
  for (const AnchorPair& a : anchors) {
    const int p = nearest_voxel(v0, a.source), q = nearest_voxel(v1, a.target);
    if (taken0[p] || taken1[q]) continue;
    taken0[p] = taken1[q] = 1;
    a0.push_back(p);
    a1.push_back(q);
    m.anchors.push_back(a);
  }
  ctx.report("harmonic fields", 0.0);
  const Eigen::MatrixXd h0 = harmonic_fields(v0, a0), h1 = harmonic_fields(v1, a1);
  ctx.report("transport", 0.0);
  const std::vector<int> l0 = part_labels(v0, m.source_skeleton, m.source_branches, m.matching.branches, true);
  const std::vector<int> l1 = part_labels(v1, m.target_skeleton, m.target_branches, m.matching.branches, false);
  int parts = o.part_transport ? std::max(1, static_cast<int>(m.matching.branches.size())) : 1;
  std::vector<std::vector<int>> members0(parts), members1(parts);
  for (size_t i = 0; i < l0.size(); ++i) members0[o.part_transport ? l0[i] : 0].push_back(static_cast<int>(i));
  for (size_t j = 0; j < l1.size(); ++j) members1[o.part_transport ? l1[j] : 0].push_back(static_cast<int>(j));
  // A part empty on one side hands its voxels to the largest part of that side.
  auto largest = [](const std::vector<std::vector<int>>& mem) {
    size_t best = 0;
    for (size_t q = 1; q < mem.size(); ++q)
      if (mem[q].size() > mem[best].size()) best = q;
    return best;
  };
  for (int q = 0; q < parts; ++q)
    if (members0[q].empty() != members1[q].empty()) {
      auto& mem = members0[q].empty() ? members1 : members0;
      auto& other = members0[q].empty() ? members0 : members1;
      size_t dst = largest(other);
      auto& moving = mem[q];
      std::vector<int>& into = mem[dst];
      into.insert(into.end(), moving.begin(), moving.end());
      std::sort(into.begin(), into.end());
      moving.clear();
    }
  std::vector<Vec3> dest0(v0.sample.size(), Vec3::Zero()), dest1(v1.sample.size(), Vec3::Zero());
  std::vector<double> w0(v0.sample.size(), 0), w1(v1.sample.size(), 0);
  const double threshold = 0.002 * static_cast<double>(a0.size());
  double agree = 0;
  m.parts = 0;
  for (int q = 0; q < parts; ++q) {
    const auto& s0 = members0[q];
    const auto& s1 = members1[q];
    if (s0.empty() || s1.empty()) continue;
    ++m.parts;
    Eigen::MatrixXd cost(s0.size(), s1.size());
    for (size_t i = 0; i < s0.size(); ++i)
      for (size_t j = 0; j < s1.size(); ++j)
        cost(i, j) = (h0.row(s0[i]) - h1.row(s1[j])).norm() +
                     o.position_weight * (v0.position(s0[i]) - v1.position(s1[j])).norm() / diagonal;
    const TransportResult r = solve_transport(cost);
    const double part_mass = static_cast<double>(s0.size()) / v0.sample.size();
    m.transport_cost += part_mass * r.cost;
    for (const Flow& f : r.flows) {
      const int i = s0[f.from], j = s1[f.to];
      dest0[i] += f.mass * v1.position(j);
      w0[i] += f.mass;
      dest1[j] += f.mass * v0.position(i);
      w1[j] += f.mass;
      if ((h0.row(i) - h1.row(j)).norm() <= threshold) agree += part_mass * f.mass;
    }
    ctx.report("transport", (q + 1.0) / parts);
  }
  m.harmonic_agreement = agree;
  for (size_t i = 0; i < dest0.size(); ++i) dest0[i] = w0[i] > 0 ? Vec3(dest0[i] / w0[i]) : v0.position(static_cast<int>(i));
  for (size_t j = 0; j < dest1.size(); ++j) dest1[j] = w1[j] > 0 ? Vec3(dest1[j] / w1[j]) : v1.position(static_cast<int>(j));
  ctx.report("warp", 0.0);
  if (o.interpolation == Interpolation::Arap) {
    build_arap_warp(m, v0, dest0, v1, dest1, box, o);
    if (!m.arap.empty()) {
      ctx.report("warp", 1.0);
      return;
    }
  }
  if (o.bone_segments > 0 && !m.matching.branches.empty()) {
    m.bones = branch_bones(m.source_skeleton, m.source_branches, m.target_skeleton, m.target_branches, m.matching,
                           m.source_sdf, m.target_sdf, o.bone_segments, m.source_sdf.spacing);
    m.bone_grid = grid_over(box, std::max(16, o.grid / 2), 1);
    const std::vector<Bone> back = inverse_bones(m.bones);
    for (double s : {0.5, 1.0})
      m.bone_min_det = std::min({m.bone_min_det, min_jacobian(frame_bone_warp(m.bones, m.bone_grid, s, o.sdf.threads)),
                                 min_jacobian(frame_bone_warp(back, m.bone_grid, s, o.sdf.threads))});
    if (m.bone_min_det > 0) {
      ctx.report("warp", 1.0);
      return;
    }
    m.bones.clear();  // the part warp folds: the linear warp below (bone_min_det says why)
  }
  m.source_warp = extend_displacement(v0, dest0);
  m.target_warp = extend_displacement(v1, dest1);
  m.source_folds = remove_folds(m.source_warp);
  m.target_folds = remove_folds(m.target_warp);
  if (m.source_folds.min_det <= 0 || m.target_folds.min_det <= 0)
    throw SolverError("warp: the displacement still folds after " +
                      std::to_string(std::max(m.source_folds.smoothing_steps, m.target_folds.smoothing_steps)) +
                      " smoothing steps (min det " + std::to_string(std::min(m.source_folds.min_det, m.target_folds.min_det)) + ")");
  ctx.report("warp", 1.0);
}

// Marks every sample reachable from those on `stack` along the 14 lattice neighbours through
// samples where take(sample) holds, emptying the stack; each newly marked sample is appended to
// `reached` when given.
template <class Take>
void flood14(const Grid& g, std::vector<size_t>& stack, std::vector<char>& mark, Take take,
             std::vector<size_t>* reached = nullptr) {
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  while (!stack.empty()) {
    const size_t s = stack.back();
    stack.pop_back();
    if (reached) reached->push_back(s);
    const int i = static_cast<int>(s % nx), j = static_cast<int>((s / nx) % ny), k = static_cast<int>(s / (static_cast<size_t>(nx) * ny));
    for (const auto& o : kNeighbours14) {
      const int a = i + o[0], b = j + o[1], c = k + o[2];
      if (a < 0 || b < 0 || c < 0 || a >= nx || b >= ny || c >= nz) continue;
      const size_t t = g.index(a, b, c);
      if (mark[t] || !take(t)) continue;
      mark[t] = 1;
      stack.push_back(t);
    }
  }
}

// Inside samples for the positive (outside) samples that no path of positive samples along the
// edges of the Kuhn tetrahedra (the 14 neighbours of the polygonization's lattice) joins to the
// grid's boundary: such a region's zero set would be an inner shell, a cavity, which neither input
// has (both are one closed component); and outside samples for islands of at most kSpeck inside
// samples or kSpeckShare of the inside samples (below the grid's resolution). Only between the ends: at the ends a pocket that the
// sampling closes (between an elephant's ear and head) and a speck are the inputs' own.
// Returns the number of samples changed.
size_t fill_cavities(Grid& g) {
  const int nx = g.dims[0], ny = g.dims[1], nz = g.dims[2];
  std::vector<char> out(g.size(), 0);
  std::vector<size_t> stack;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        if ((i == 0 || j == 0 || k == 0 || i == nx - 1 || j == ny - 1 || k == nz - 1) && g.values[g.index(i, j, k)] >= 0) {
          out[g.index(i, j, k)] = 1;
          stack.push_back(g.index(i, j, k));
        }
  flood14(g, stack, out, [&](size_t t) { return g.values[t] >= 0; });
  size_t changed = 0;
  const float inside = -static_cast<float>(g.spacing);
  for (size_t s = 0; s < g.size(); ++s)
    if (!out[s] && g.values[s] >= 0) {
      g.values[s] = inside;
      ++changed;
    }
  // Islands of inside samples (joined the same way) up to kSpeck samples or kSpeckShare of the
  // frame's inside samples are specks, not parts of either shape: what a warp's fold or a
  // part thinner than the grid leaves behind when the blend thins it (the camel's tail between
  // t = 0.8 and 0.9: 0.02-0.05% of the frame's volume); a part that comes off (a head, several %)
  // is kept, and shows.
  size_t inside_samples = 0;
  for (float v : g.values) inside_samples += v < 0;
  const size_t speck = std::max(kSpeck, static_cast<size_t>(kSpeckShare * static_cast<double>(inside_samples)));
  std::vector<char> seen(g.size(), 0);
  std::vector<size_t> island;
  const float outside = static_cast<float>(g.spacing);
  for (size_t s0 = 0; s0 < g.size(); ++s0) {
    if (seen[s0] || g.values[s0] >= 0) continue;
    island.clear();
    stack.push_back(s0);
    seen[s0] = 1;
    flood14(g, stack, seen, [&](size_t t) { return g.values[t] < 0; }, &island);
    if (island.size() <= speck)
      for (size_t s : island) g.values[s] = outside, ++changed;
  }
  return changed;
}


// The bone warp at s, smoothed (blending the bones' transforms leaves creases where the nearest
// bone changes).
Displacement frame_bone_warp(const std::vector<Bone>& bones, const Grid& geometry, double s, int threads) {
  Displacement d = bone_displacement(bones, geometry, s, threads);
  const double cells = std::max({geometry.dims[0], geometry.dims[1], geometry.dims[2]}) - 3.0;
  jacobi_smooth(d, std::max(1, static_cast<int>(std::lround(kBoneSmoothing * (cells / 75) * (cells / 75)))));
  repair_folds_locally(d);  // bones.h
  return d;
}

}  // namespace

Similarity Similarity::inverse() const {
  Similarity r;
  r.scale = 1 / scale;
  r.rotation = rotation.transpose();
  r.from = to;
  r.to = from;
  return r;
}

Similarity Similarity::after(const Similarity& first) const {
  Similarity r;
  r.scale = scale * first.scale;
  r.rotation = rotation * first.rotation;
  r.from = first.from;
  r.to = apply(first.to);
  return r;
}

Vec3 placement(const Similarity& s, double t, const Vec3& y) {
  const double scale = (1 - t) + t * s.scale;
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity().slerp(t, Eigen::Quaterniond(s.rotation));
  const Vec3 centre = (1 - t) * s.to + t * s.from;
  return centre + q.conjugate() * (y - s.to) / scale;
}

namespace {

// x -> (x - centre) / diagonal: the box's centre to the origin, its diagonal to 1.
Similarity unit_box(const Box3& box, const char* what) {
  const Vec3 extent = box.max - box.min;
  const double longest = extent.cwiseAbs().maxCoeff();
  const double d = longest > 0 ? longest * (extent / longest).norm() : 0.0;  // no overflow near 1e308
  if (!(d > 0) || !std::isfinite(d) || !std::isfinite(1 / d))
    throw InvalidInput(std::string(what) + ": its bounding box has diagonal " + std::to_string(d) +
                       "; expected a positive, finite size");
  Similarity s;
  s.scale = 1 / d;
  s.from = 0.5 * (box.min + box.max);
  return s;
}

TriMesh moved_by(const TriMesh& m, const Similarity& s) {
  TriMesh out = m;
  for (Vec3& p : out.positions) p = s.apply(p);
  return out;
}

bool finite(const Similarity& s) {
  return std::isfinite(s.scale) && s.scale > 0 && s.rotation.allFinite() && s.from.allFinite() && s.to.allFinite();
}

// The shapes placed as the morph places them (prepare_morph's first step).
struct Placed {
  Similarity source_to_morph, target_to_morph, target_to_source;
  TriMesh source, target;  // in morph space
  TriMesh unit_source, unit_target;  // each scaled to unit size on its own
  Similarity unit_source_to_morph, unit_target_to_morph;
  Vec3 source_centroid = Vec3::Zero();
  double source_volume = 0, target_volume = 0;  // in the inputs' own units
  Box3 box;                                     // around both, in morph space
};

// Each shape is scaled to unit size on its own first: volumes, centroids, principal axes and the
// rotation search see numbers near 1 whatever the inputs' magnitude. The alignment found there is
// carried back to the inputs' units (target_to_source), and morph space is the source's units
// scaled so that the box around the source and the placed target has diagonal 1.
Placed place_shapes(const TriMesh& source, const TriMesh& target, Align align) {
  const Similarity ns = unit_box(bounding_box(source.positions), "source");
  const Similarity nt = unit_box(bounding_box(target.positions), "target");
  const TriMesh s1 = moved_by(source, ns), t1 = moved_by(target, nt);
  double vs = 0, vt = 0;
  const Vec3 c0 = volume_centroid(s1, vs);
  const Vec3 c1 = volume_centroid(t1, vt);
  if (!(vs > 0) || !(vt > 0))
    throw InvalidInput("a shape encloses no volume (source " + std::to_string(vs) + ", target " + std::to_string(vt) +
                       " of its bounding box's diagonal cubed)");
  Placed p;
  p.source_volume = vs / (ns.scale * ns.scale * ns.scale);
  p.target_volume = vt / (nt.scale * nt.scale * nt.scale);
  Similarity t_to_s;  // unit target -> unit source
  if (align == Align::Similarity) {
    t_to_s.scale = std::cbrt(vs / vt);
    t_to_s.from = c1;
    t_to_s.to = c0;
    t_to_s.rotation = best_rotation(s1, c0, t1, c1, t_to_s.scale);
  } else {
    t_to_s = ns.after(nt.inverse());
  }
  p.target_to_source = ns.inverse().after(t_to_s.after(nt));
  const TriMesh moved = moved_by(t1, t_to_s);  // in the unit source's space
  Box3 box = bounding_box(s1.positions);
  const Box3 b1 = bounding_box(moved.positions);
  box.min = box.min.cwiseMin(b1.min);
  box.max = box.max.cwiseMax(b1.max);
  const Similarity to_morph = unit_box(box, "the two shapes together");
  p.source_to_morph = to_morph.after(ns);
  p.target_to_morph = to_morph.after(t_to_s.after(nt));
  if (!finite(p.target_to_source) || !finite(p.source_to_morph) || !finite(p.target_to_morph))
    throw InvalidInput("the shapes' sizes differ by more than double precision can scale (source diagonal " +
                       std::to_string(1 / ns.scale) + ", target " + std::to_string(1 / nt.scale) + ")");
  p.source = moved_by(s1, to_morph);
  p.target = moved_by(moved, to_morph);
  p.unit_source = s1;
  p.unit_target = t1;
  p.unit_source_to_morph = to_morph;
  p.unit_target_to_morph = to_morph.after(t_to_s);
  p.source_centroid = to_morph.apply(c0);
  p.box = bounding_box(p.source.positions);
  const Box3 b2 = bounding_box(p.target.positions);
  p.box.min = p.box.min.cwiseMin(b2.min);
  p.box.max = p.box.max.cwiseMax(b2.max);
  return p;
}

void check_morph_options(const MorphOptions& options) {
  if (options.grid < 8 || options.grid > 1024)
    throw InvalidInput("grid is " + std::to_string(options.grid) + " cells; expected 8 to 1024");
  if (options.pad < 2) throw InvalidInput("pad is " + std::to_string(options.pad) + " cells; expected at least 2");
  if (!(options.max_iso_shift >= 0 && options.max_iso_shift <= 64))
    throw InvalidInput("max_iso_shift is " + std::to_string(options.max_iso_shift) + " cells; expected 0 to 64");
}

// endpoint_frame's grid over an input of `box` (its own units) at `voxel` (its own units).
Grid endpoint_domain(const Box3& box, double voxel) {
  const double longest = (box.max - box.min).maxCoeff();
  const double cells = std::ceil(longest / voxel);
  if (!(cells <= 2048))
    throw InvalidInput("endpoint grid of " + std::to_string(cells) + " cells; expected at most 2048 (lower the refinement)");
  return grid_over(box, std::max(8, static_cast<int>(cells)), 3);
}

}  // namespace

PreparedMorph prepare_morph(const TriMesh& source, const TriMesh& target, const MorphOptions& options,
                            const Context& ctx) {
  check_morph_options(options);
  PreparedMorph m;
  m.volume = options.volume;
  m.max_iso_shift = options.max_iso_shift;
  m.topology_control = options.topology_control;
  m.source_genus = mesh_stats(source).genus;
  m.target_genus = mesh_stats(target).genus;
  const Placed p = place_shapes(source, target, options.align);
  m.target_to_source = p.target_to_source;
  m.source_to_morph = p.source_to_morph;
  m.target_to_morph = p.target_to_morph;
  m.source_centroid = p.source_centroid;
  m.source_volume = p.source_volume;
  m.target_volume = p.target_volume;
  if (options.warp) {
    check_correspondence_options(options);
    build_skeletons(m, p.unit_source, p.unit_source_to_morph, p.unit_target, p.unit_target_to_morph, options, ctx);
  }
  const Grid domain = grid_over(p.box, options.grid, options.pad);
  ctx.report("distance fields", 0.0);
  m.source_sdf = signed_distance(p.source, domain, options.sdf, ctx.without_progress());
  ctx.report("distance fields", 0.5);
  m.target_sdf = signed_distance(p.target, domain, options.sdf, ctx.without_progress());
  ctx.report("distance fields", 1.0);
  if (options.warp) build_correspondence(m, p.source, options, ctx);
  return m;
}

MorphSize morph_size(const TriMesh& source, const TriMesh& target, const MorphOptions& options, int endpoint_refine) {
  check_morph_options(options);
  if (endpoint_refine < 1 || endpoint_refine > 8)
    throw InvalidInput("endpoint refinement is " + std::to_string(endpoint_refine) + "; expected 1 to 8");
  const Placed p = place_shapes(source, target, options.align);
  MorphSize s;
  const Grid domain = grid_over(p.box, options.grid, options.pad);
  s.grid_dims = domain.dims;
  s.spacing = domain.spacing;
  s.source_area = surface_area(p.source);
  s.target_area = surface_area(p.target);
  if (endpoint_refine > 1) {
    s.source_end_dims = endpoint_domain(bounding_box(p.source.positions), domain.spacing / endpoint_refine).dims;
    s.target_end_dims = endpoint_domain(bounding_box(p.target.positions), domain.spacing / endpoint_refine).dims;
  }
  return s;
}

double estimate_memory(const MorphSize& s, const MemoryRequest& r, bool warp) {
  const auto samples = [](const std::array<int, 3>& d) { return static_cast<double>(d[0]) * d[1] * d[2]; };
  const double n = samples(s.grid_dims);
  const double h = s.spacing;
  const double area = std::max(s.source_area, s.target_area);
  // Vertices of a polygonized frame: about 4.5 per (area / spacing^2) measured; 6 counted.
  const double v_mid = 6 * area / (h * h);
  const double refine = std::max(1, r.endpoint_refine);
  const double v_end = v_mid * refine * refine;
  const double m_end = r.endpoint_refine > 1 ? std::max(samples(s.source_end_dims), samples(s.target_end_dims)) : 0.0;
  // Bytes: two float fields held throughout (8 per sample); a signed distance field being built
  // (22 per sample: closest points, distances, flags, values); a frame's blend (warped copies,
  // the blend, flood-fill marks and stacks, the polygonizer's copy: 28 per sample, 20 without the
  // warp); a polygonization (150 per vertex: the mesh and its edge table).
  const double fields = 8 * n;
  const double sdf = 22 * n;
  const double blend = (warp ? 28 : 20) * n + 150 * v_mid;
  const double ends = 22 * m_end + 16 * m_end + 150 * v_end;
  double retime = 0;
  if (r.even_timing && r.frames > 2) {
    const double c = std::max(1, r.coarsen);
    const double dense = (1.0 + std::max(0, r.refine_passes)) * std::max(1, r.samples_per_frame) * (r.frames - 1.0) + 1;
    // Each dense frame keeps its mesh (64 bytes per vertex); two distance structures (400 per
    // vertex) and a coarse blend at a time.
    const double v_coarse = v_mid / (c * c);
    retime = dense * 64 * v_coarse + 2 * 400 * v_coarse + (8 + (warp ? 28 : 20)) * n / (c * c * c);
  }
  double kept = 0;
  if (r.keep_frames) kept = 250 * (std::max(0, r.frames - 2) * v_mid + 2 * v_end);
  const double total = 32.0 * 1024 * 1024 + fields + std::max({sdf, blend, ends, retime}) + kept;
  return std::isfinite(total) ? total : std::numeric_limits<double>::max();
}

double volume_below(const Grid& field, double c) {
  const double h = field.spacing, cell = h * h * h;
  double sum = 0;
  for (float v : field.values) sum += std::clamp(0.5 + (c - v) / h, 0.0, 1.0);
  return cell * sum;
}

double iso_for_volume(const Grid& field, double volume, double max_shift) {
  const double h = field.spacing, cell = h * h * h;
  max_shift = std::max(0.0, max_shift);
  // Samples that are inside (or outside) for every c in [-max_shift, max_shift] once; the band
  // between them is what the bisection sums, in the grid's order (deterministic).
  double inside = 0;
  std::vector<double> band;
  for (float v : field.values) {
    if (v <= -max_shift - 0.5 * h) inside += 1;
    else if (v < max_shift + 0.5 * h) band.push_back(v);
  }
  const auto below = [&](double c) {
    double sum = inside;
    for (double v : band) sum += std::clamp(0.5 + (c - v) / h, 0.0, 1.0);
    return cell * sum;
  };
  double lo = -max_shift, hi = max_shift;
  if (below(hi) <= volume) return hi;
  if (below(lo) >= volume) return lo;
  while (hi - lo > 1e-6 * h) {
    const double mid = 0.5 * (lo + hi);
    (below(mid) < volume ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

Grid blend_field(const PreparedMorph& m, double t, int threads, BlendInfo* info) {
  if (info) *info = BlendInfo{};
  Grid g = m.source_sdf;
  if (!m.arap.empty()) {
    // D_t(q) = (1 - t) D_0(B_0^t(q)) + t D_1(B_1^t(q)); the ends are the inputs' fields exactly.
    if (t <= 0 || t >= 1) {
      g = t <= 0 ? m.source_sdf : m.target_sdf;
    } else {
      const std::array<Displacement, 2> back = arap_backward(m, t, m.bone_grid, threads);
      const Grid a = pulled_field(m.source_sdf, back[0], threads), b = pulled_field(m.target_sdf, back[1], threads);
      for (size_t i = 0; i < g.values.size(); ++i)
        g.values[i] = static_cast<float>((1 - t) * a.values[i] + t * b.values[i]);
    }
  } else if (!m.bones.empty()) {
    // The ends are the inputs' fields exactly (no resampling at a zero warp).
    const Grid a = t == 0 ? m.source_sdf
                          : warped_field_newton(m.source_sdf, frame_bone_warp(m.bones, m.bone_grid, t, threads), threads);
    const Grid b = t == 1 ? m.target_sdf
                          : warped_field_newton(m.target_sdf, frame_bone_warp(inverse_bones(m.bones), m.bone_grid, 1 - t, threads),
                                                threads);
    for (size_t i = 0; i < g.values.size(); ++i)
      g.values[i] = static_cast<float>((1 - t) * a.values[i] + t * b.values[i]);
  } else if (m.warp) {
    const Grid a = warped_field(m.source_sdf, m.source_warp, t, threads);
    const Grid b = warped_field(m.target_sdf, m.target_warp, 1 - t, threads);
    for (size_t i = 0; i < g.values.size(); ++i)
      g.values[i] = static_cast<float>((1 - t) * a.values[i] + t * b.values[i]);
  } else {
    for (size_t i = 0; i < g.values.size(); ++i)
      g.values[i] = static_cast<float>((1 - t) * m.source_sdf.values[i] + t * m.target_sdf.values[i]);
  }
  // The frame's volume: where neither warped shape covers the other (parts that do not overlap
  // half-way), the blend of two distance fields is positive and the frame thins or loses them;
  // shifting its iso level by one constant brings the enclosed volume back to the linear
  // interpolation of the ends' (measured with the same estimator on both, so its bias cancels).
  if (m.volume == FrameVolume::Linear && t > 0 && t < 1) {
    const double wanted = (1 - t) * volume_below(m.source_sdf) + t * volume_below(m.target_sdf);
    const double shift = iso_for_volume(g, wanted, m.max_iso_shift * g.spacing);
    if (info) {
      info->volume_wanted = wanted;
      info->volume_blended = volume_below(g);
      info->iso_shift = shift;
      info->clamped = std::abs(shift) >= m.max_iso_shift * g.spacing;
    }
    const float s = static_cast<float>(shift);
    for (float& v : g.values) v -= s;
  }
  const float floor = static_cast<float>(g.spacing);
  for (int k = 0; k < g.dims[2]; ++k)
    for (int j = 0; j < g.dims[1]; ++j)
      for (int i = 0; i < g.dims[0]; ++i)
        if (i == 0 || j == 0 || k == 0 || i == g.dims[0] - 1 || j == g.dims[1] - 1 || k == g.dims[2] - 1)
          g.values[g.index(i, j, k)] = std::max(g.values[g.index(i, j, k)], floor);
  if (t > 0 && t < 1) fill_cavities(g);  // the ends stay the inputs' fields as sampled
  if (controls_topology(m, t)) {
    const BallReport ball = make_ball(g);
    if (info) info->topology_controlled = true, info->ball = ball;
  }
  return g;
}

bool controls_topology(const PreparedMorph& m, double t) {
  if (!m.topology_control) return false;
  if (t <= 0) return m.source_genus == 0;
  if (t >= 1) return m.target_genus == 0;
  return m.source_genus == 0 && m.target_genus == 0;
}

TriMesh frame_mesh(const PreparedMorph& m, const Grid& field, double t, const PolygonizeOptions& options) {
  TriMesh mesh = polygonize(field, options);
  const Similarity back = m.source_to_morph.inverse();
  for (Vec3& p : mesh.positions) {
    p = placement(m.target_to_source, t, back.apply(p));
    if (!p.allFinite()) throw InvalidInput("frame at t = " + std::to_string(t) + ": a position is not finite in the inputs' units");
  }
  return mesh;
}

TriMesh endpoint_frame(const PreparedMorph& m, const TriMesh& input, bool is_target, int refine, const SdfOptions& sdf,
                       const PolygonizeOptions& options, BallReport* ball) {
  if (refine < 1 || refine > 8) throw InvalidInput("endpoint refinement is " + std::to_string(refine) + "; expected 1 to 8");
  // The morph's voxel in the input's units, and the input scaled to unit size.
  const double voxel = m.source_sdf.spacing / (is_target ? m.target_to_morph.scale : m.source_to_morph.scale) / refine;
  const Similarity unit = unit_box(bounding_box(input.positions), is_target ? "target" : "source");
  const TriMesh scaled = moved_by(input, unit);
  const Grid domain = endpoint_domain(bounding_box(scaled.positions), voxel * unit.scale);
  Grid field = signed_distance(scaled, domain, sdf);
  if (ball) *ball = BallReport{};
  if (controls_topology(m, is_target ? 1.0 : 0.0)) {
    const BallReport r = make_ball(field, {}, options);
    if (ball) *ball = r;
  }
  TriMesh mesh = polygonize(field, options);
  const Similarity back = unit.inverse();
  for (Vec3& p : mesh.positions) p = back.apply(p);
  return mesh;
}

}  // namespace qs::dfi
