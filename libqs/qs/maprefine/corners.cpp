// Corner moves: the k patches around a corner glued into one disk chart, refined and cut again
// along k rays (RefineOptions::move_corners).
#include "qs/maprefine/map_refine_detail.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "qs/core/parallel.h"
#include "qs/param/square_param.h"

namespace qs::maprefine {

namespace {

// ---- Corner moves (cone charts) -----------------------------------------------------------------
//
// The k patches around a corner c are glued into one disk: patch j's square turned so that c is at
// its origin and its sides from c lie along +x and +y, then mapped by z -> z^(4/k) rotated by
// 2 pi j / k (sector j). Consecutive patches share the side between them: patch j's +y side is
// patch j+1's +x side, the ray at angle 2 pi (j+1) / k. B's (u, v) is refined on the union with
// the outer border held, then the union is cut again along the k rays.

// The unit vector at angle a pi / k, exact on the axes.
Vec2 half_step_dir(int a, int k) {
  a = ((a % (2 * k)) + 2 * k) % (2 * k);
  if ((2 * a) % k == 0) {
    switch ((2 * a / k) & 3) {
      case 0: return Vec2(1, 0);
      case 1: return Vec2(0, 1);
      case 2: return Vec2(-1, 0);
      default: return Vec2(0, -1);
    }
  }
  const double t = M_PI * a / k;
  return Vec2(std::cos(t), std::sin(t));
}

}  // namespace

Vec2 sector_glue(const Vec2& q, int k, int sector) {
  if (q.x() == 0 && q.y() == 0) return Vec2::Zero();
  const Vec2 a = half_step_dir(2 * sector, k), b = half_step_dir(2 * (sector + 1), k);
  if (q.y() == 0) return q.x() * a;
  if (q.x() == 0) return q.y() * b;
  return q.x() * a + q.y() * b;
}

Vec2 sector_unglue(const Vec2& g, int k, int sector) {
  const Vec2 a = half_step_dir(2 * sector, k), b = half_step_dir(2 * (sector + 1), k);
  const double d = cross2(a, b);
  return Vec2(cross2(g, b) / d, cross2(a, g) / d);
}

namespace detail {

namespace {

// The patches around a corner in counter-clockwise order: patch j has the corner as its corner
// index[j]; patch j's side index[j] - 1 (into the corner) is patch j+1's side index[j+1] (out of it).
struct CornerStar {
  int corner = -1;
  std::vector<int> patches, index;
};

using DirectedSides = std::map<std::pair<int, int>, std::vector<std::pair<int, int>>>;

DirectedSides directed_sides(const dissect::Chart& chart) {
  DirectedSides out;
  for (int p = 0; p < static_cast<int>(chart.patches.size()); ++p)
    for (int m = 0; m < 4; ++m) {
      const auto& c = chart.patches[p].corners;
      out[{c[m], c[(m + 1) % 4]}].push_back({p, m});
    }
  return out;
}

// The star of corner c (first met as corner m of patch p), or nullopt when irregular: fewer than 3
// patches, a patch met twice, a side met twice, or a cycle that does not close over every patch
// that has c as a corner.
std::optional<CornerStar> corner_star(const dissect::Chart& chart, const DirectedSides& sides, int p, int m) {
  CornerStar star;
  star.corner = chart.patches[p].corners[m];
  int count = 0;
  for (const auto& info : chart.patches)
    for (int x : info.corners) count += x == star.corner;
  int cp = p, cm = m;
  while (true) {
    if (std::find(star.patches.begin(), star.patches.end(), cp) != star.patches.end()) return std::nullopt;
    star.patches.push_back(cp);
    star.index.push_back(cm);
    const int prev = chart.patches[cp].corners[(cm + 3) % 4];
    const auto it = sides.find({star.corner, prev});
    if (it == sides.end() || it->second.size() != 1) return std::nullopt;
    cp = it->second[0].first;
    cm = it->second[0].second;
    if (cp == p) {
      if (cm != m) return std::nullopt;
      break;
    }
    if (static_cast<int>(star.patches.size()) > count) return std::nullopt;
  }
  const int k = static_cast<int>(star.patches.size());
  if (k < 3 || k != count) return std::nullopt;
  return star;
}

enum class CornerOutcome { Moved, Unchanged, Irregular, Skipped };

struct CornerCut {
  SideCut cut;
  CornerOutcome outcome = CornerOutcome::Unchanged;
  int new_corner = -1;  // local id of the new corner (>= cut.vertices.size(): a new vertex)
  CornerCut& with(CornerOutcome o) {
    outcome = o;
    return *this;
  }
};

// A piece of a cut is a needle when its height is below this fraction of its longest edge.
constexpr double kNeedle = 1e-3;
// A snapped vertex keeps at least this fraction of the uv area of each of its faces.
constexpr double kSnapKeep = 0.5;

// Where a glued vertex lies: the origin, a generic point, or on the line at angle a pi / k
// (a = 2 j: ray j; for odd k, a odd: the continuation of a ray through the origin).
constexpr int kOrigin = -2, kGeneric = -1;

// Refines B's map on the star of a corner and plans the cut along the k rays (see above). `pinned`:
// corners, seeds and features of B. Only an outcome Moved has a cut to commit.
CornerCut plan_corner(const dissect::Chart& chart, const ChartIndex& index, const std::vector<ReferencePatch>& refs,
                      const CornerStar& star, const std::vector<char>& pinned, const RefineOptions& options,
                      const PosePull* pull) {
  CornerCut out;
  const int k = static_cast<int>(star.patches.size());
  auto glue = [&](const Vec2& q, int j) { return sector_glue(q, k, j); };
  auto unglue = [&](const Vec2& g, int j) { return sector_unglue(g, k, j); };
  std::vector<Eigen::Matrix2d> sector_inverse(k);  // the sector glue's inverse Jacobian
  for (int j = 0; j < k; ++j) {
    Eigen::Matrix2d d;
    d.col(0) = half_step_dir(2 * j, k);
    d.col(1) = half_step_dir(2 * (j + 1), k);
    sector_inverse[j] = d.inverse();
  }
  const int nv = chart.mesh.num_vertices();
  std::vector<int> turns(k);
  std::unordered_map<int, int> sector_of;
  for (int j = 0; j < k; ++j) {
    turns[j] = (4 - star.index[j]) % 4;
    sector_of[star.patches[j]] = j;
  }
  std::vector<char> outside(nv, 0);
  const std::vector<int> faces = index.gather(chart, star.patches, outside);
  PatchProblem pr;
  std::unordered_map<int, int> local;
  std::vector<int> tag;
  std::vector<char> held;
  std::vector<char> has_wedge;  // per local vertex and sector
  std::vector<Vec2> wedge;
  std::vector<int> face_sector;
  for (int f : faces) {
    const int w = sector_of[chart.face_patch[f]];
    std::array<int, 3> c{};
    for (int i = 0; i < 3; ++i) {
      const int v = chart.mesh.faces[f][i];
      const Vec2& s = chart.face_uv[f][i];
      const Vec2 q = turn_square(s, turns[w]);
      const Vec2 g = glue(q, w);
      const int t = q.x() == 0 && q.y() == 0 ? kOrigin : q.y() == 0 ? 2 * w : q.x() == 0 ? 2 * ((w + 1) % k) : kGeneric;
      auto [it, added] = local.try_emplace(v, static_cast<int>(pr.vertices.size()));
      const int l = it->second;
      if (added) {
        pr.vertices.push_back(v);
        pr.uv.push_back(g);
        tag.push_back(t);
        held.push_back(outside[v] || (pinned[v] && v != star.corner));
        has_wedge.resize(has_wedge.size() + k, 0);
        wedge.resize(wedge.size() + k, Vec2::Zero());
      }
      const size_t slot = static_cast<size_t>(l) * k + w;
      if (!has_wedge[slot]) {
        if (!added && (pr.uv[l] - g).norm() > 1e-9) return out.with(CornerOutcome::Irregular);
        if (!added && tag[l] == kGeneric) tag[l] = t;
        has_wedge[slot] = 1;
        wedge[slot] = s;
      } else if (wedge[slot] != s) {
        held[l] = 1;  // wedges of one patch disagree: hold it
      }
      c[i] = l;
    }
    pr.add_face(chart, f, chart.face_patch[f], c);
    face_sector.push_back(w);
  }
  pr.add_unknowns(held);
  const int nl = static_cast<int>(pr.vertices.size());
  const auto corner_local = local.find(star.corner);
  if (pr.unknowns == 0 || corner_local == local.end() || held[corner_local->second])
    return out.with(CornerOutcome::Irregular);

  // The reference's metric glued the same way: M_glued = C^T (A M A^T) C with A the turn and C the
  // Jacobian of the inverse sector glue (evaluated at face centroids).
  double area_a = 0;
  for (int p : star.patches) area_a += refs[p].area();
  const double scale = area_a > 0 ? pr.total_area / area_a : 1.0;
  std::vector<Eigen::Matrix2d> lin(k);
  for (int j = 0; j < k; ++j) lin[j] = Glue{star.patches[j], turns[j], 0.0}.linear();
  // A metric ms of patch star.patches[j] at glued point g, in glued (u, v).
  auto glued_metric = [&](int j, const Eigen::Matrix2d& ms) {
    const Eigen::Matrix2d& c = sector_inverse[j];
    return Eigen::Matrix2d(c.transpose() * lin[j] * ms * lin[j].transpose() * c);
  };
  auto hints = std::make_shared<std::vector<int>>(pr.faces.size() * k, -1);
  const MetricFn metric = [&, hints](size_t t, const Vec2& g) {
    double ang = std::atan2(g.y(), g.x());
    if (ang < 0) ang += 2 * M_PI;
    const int j = std::clamp(static_cast<int>(std::floor(ang / (2 * M_PI / k))), 0, k - 1);
    const Vec2 q = unglue(g, j);
    const Vec2 s = turn_square(q.cwiseMax(0.0).cwiseMin(1.0), 4 - turns[j]);
    return Eigen::Matrix2d(scale * glued_metric(j, refs[star.patches[j]].metric(s, (*hints)[t * k + j])));
  };
  if (pull) {
    // The pose pull toward the nearest of the reference's k patches around the corner, glued.
    add_pull(pr, chart, *pull, [&](int, const Vec3& y, const Vec3& n) {
      return nearest_of(
          *pull, k, y, n, [&](int j) { return star.patches[j]; },
          [&](int j, const PullTarget& t) {
            const Vec2 g = glue(turn_square(t.uv, turns[j]), j);
            return PullTarget{g, glued_metric(j, t.metric), t.distance};
          });
    });
  }
  const std::vector<Vec2> start = pr.uv;
  RefineOptions corner_options = options;
  corner_options.iterations = std::min(options.iterations, options.corner_iterations);
  const PatchResult res = solve_problem(pr, metric, corner_options, true, Vec2(4, 4), Vec2(-4, -4));
  out.cut.steps = res.steps;
  if (res.skipped) return out.with(CornerOutcome::Skipped);
  if (!res.changed) return out.with(CornerOutcome::Unchanged);
  std::vector<Vec2> uv = pr.uv;
  for (int l = 0; l < nl; ++l)
    if (held[l]) uv[l] = start[l];  // exactly as they were
    else tag[l] = kGeneric;

  // Sub-triangles (the face holding the origin is split there), with the chart face they come from.
  std::vector<std::array<int, 3>> tri = pr.tri;
  std::vector<int> tri_face(tri.size());
  for (size_t t = 0; t < tri.size(); ++t) tri_face[t] = static_cast<int>(t);
  std::vector<std::vector<int>> vertex_tris(nl);
  for (size_t t = 0; t < tri.size(); ++t)
    for (int l : tri[t]) vertex_tris[l].push_back(static_cast<int>(t));
  // A vertex may be snapped (onto the origin or a ray) when every face around it stays positive
  // and keeps at least kSnapKeep of its uv area: a snap must not crush a face, whose map would
  // then be far more distorted than the cut it saves.
  auto positive_around = [&](int l, const Vec2& was) {
    for (int t : vertex_tris[l]) {
      const auto& c = tri[t];
      const double now = tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      const Vec2 keep = uv[l];
      uv[l] = was;
      const double before = tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      uv[l] = keep;
      if (!(0.5 * now > 4 * param::kZeroUvArea) || !(now >= kSnapKeep * before)) return false;
    }
    return true;
  };
  int origin = -1;
  std::vector<Vec3> new_pos;
  {
    int best = -1;
    Vec3 bary = Vec3::Zero();
    double score = -kInf;
    for (size_t t = 0; t < tri.size(); ++t) {
      const auto& c = tri[t];
      const double a = tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      const Vec2 o = Vec2::Zero();
      const Vec3 b(tri_det(o, uv[c[1]], uv[c[2]]) / a, tri_det(uv[c[0]], o, uv[c[2]]) / a,
                   tri_det(uv[c[0]], uv[c[1]], o) / a);
      if (b.minCoeff() > score) {
        score = b.minCoeff();
        bary = b;
        best = static_cast<int>(t);
      }
    }
    if (best < 0 || score < -1e-12) return out.with(CornerOutcome::Skipped);
    const auto c = tri[best];
    int top = 0;
    for (int i = 1; i < 3; ++i)
      if (bary[i] > bary[top]) top = i;
    if (bary[top] >= 1 - kCutSnap && !held[c[top]]) {
      const Vec2 was = uv[c[top]];
      uv[c[top]] = Vec2::Zero();
      if (positive_around(c[top], was)) origin = c[top];
      else uv[c[top]] = was;
    }
    if (origin < 0) {
      if (score <= 1e-9) return out.with(CornerOutcome::Skipped);  // on an edge: no clean split
      origin = nl;
      uv.push_back(Vec2::Zero());
      tag.push_back(kOrigin);
      const auto& t = chart.mesh.faces[pr.faces[best]];
      new_pos.push_back(bary[0] * chart.mesh.positions[t[0]] + bary[1] * chart.mesh.positions[t[1]] +
                        bary[2] * chart.mesh.positions[t[2]]);
      tri[best] = {origin, c[1], c[2]};
      tri.push_back({c[0], origin, c[2]});
      tri_face.push_back(best);
      tri.push_back({c[0], c[1], origin});
      tri_face.push_back(best);
    }
    tag[origin] = kOrigin;
  }
  std::vector<Vec3> base_pos;  // 3D position per local vertex (original ones, then new ones)
  for (int l = 0; l < nl; ++l) base_pos.push_back(chart.mesh.positions[pr.vertices[l]]);
  for (const auto& p : new_pos) base_pos.push_back(p);
  vertex_tris.assign(uv.size(), {});
  for (size_t t = 0; t < tri.size(); ++t)
    for (int l : tri[t]) vertex_tris[l].push_back(static_cast<int>(t));

  // Snap free vertices near a ray onto it (as a fraction of a crossing edge's extent across it).
  std::vector<Vec2> ray(k);
  for (int j = 0; j < k; ++j) ray[j] = half_step_dir(2 * j, k);
  std::vector<std::pair<int, int>> snap;  // (local vertex, ray)
  for (const auto& c : tri)
    for (int i = 0; i < 3; ++i) {
      const int a = c[i], b = c[(i + 1) % 3];
      for (int j = 0; j < k; ++j) {
        const double sa = cross2(ray[j], uv[a]), sb = cross2(ray[j], uv[b]);
        if (!(sa * sb < 0)) continue;
        const double t = sa / (sa - sb);
        if ((uv[a] + t * (uv[b] - uv[a])).dot(ray[j]) <= 0) continue;
        if (t < kCutSnap && a < nl && !held[a] && tag[a] == kGeneric) snap.push_back({a, j});
        if (t > 1 - kCutSnap && b < nl && !held[b] && tag[b] == kGeneric) snap.push_back({b, j});
      }
    }
  std::sort(snap.begin(), snap.end());
  snap.erase(std::unique(snap.begin(), snap.end()), snap.end());
  for (const auto& [l, j] : snap) {
    if (tag[l] != kGeneric) continue;
    const Vec2 was = uv[l];
    uv[l] = std::max(uv[l].dot(ray[j]), 0.0) * ray[j];
    if (uv[l].squaredNorm() > 0 && positive_around(l, was)) tag[l] = 2 * j;
    else uv[l] = was;
  }

  // Sign of a vertex against the line through the origin along ray m (symbolic for tagged ones).
  auto side = [&](int l, int m) {
    if (tag[l] == kOrigin) return 0;
    if (tag[l] >= 0) {
      const int r = ((tag[l] - 2 * m) % (2 * k) + 2 * k) % (2 * k);
      return r == 0 || r == k ? 0 : r < k ? 1 : -1;
    }
    const double s = cross2(ray[m], uv[l]);
    return s > 0 ? 1 : s < 0 ? -1 : 0;
  };
  // Vertices on the sub-triangles' edges: a cut point lies on edge (a, b) of its sub-triangle.
  std::map<std::tuple<int, int, int>, int> cut;  // (a, b, tag), a < b by chart id -> local id
  std::vector<std::pair<int, int>> on_edge(uv.size(), {-1, -1});
  auto global = [&](int l) { return l < nl ? pr.vertices[l] : nv + (l - nl); };
  bool failed = false;
  auto cut_point = [&](int a, int b, int m) {
    if (global(a) > global(b)) std::swap(a, b);
    const double sa = cross2(ray[m], uv[a]), sb = cross2(ray[m], uv[b]);
    if (!(sa * sb < 0)) {
      failed = true;
      return a;
    }
    const double t = sa / (sa - sb);
    const Vec2 p = uv[a] + t * (uv[b] - uv[a]);
    const int dir = p.dot(ray[m]) > 0 ? 2 * m : (2 * m + k) % (2 * k);
    const auto key = std::make_tuple(a, b, dir);
    const auto it = cut.find(key);
    if (it != cut.end()) return it->second;
    const int id = static_cast<int>(uv.size());
    uv.push_back(p);
    tag.push_back(dir);
    on_edge.push_back({a, b});
    new_pos.push_back((1 - t) * base_pos[a] + t * base_pos[b]);
    base_pos.push_back(new_pos.back());
    cut.emplace(key, id);
    return id;
  };
  // The sub-triangle edge holding both polygon vertices x and y, or (-1, -1).
  auto common_edge = [&](int x, int y, const std::array<int, 3>& c) -> std::pair<int, int> {
    for (int i = 0; i < 3; ++i) {
      const int a = c[i], b = c[(i + 1) % 3];
      auto on = [&](int l) {
        if (l == a || l == b) return true;
        const auto& e = on_edge[l];
        return (e.first == a && e.second == b) || (e.first == b && e.second == a);
      };
      if (on(x) && on(y)) return {a, b};
    }
    return {-1, -1};
  };
  auto clip = [&](const std::vector<int>& poly, int m, int keep, const std::array<int, 3>& c) {
    std::vector<int> res;
    const size_t n = poly.size();
    for (size_t i = 0; i < n; ++i) {
      const int x = poly[i], y = poly[(i + 1) % n];
      const int sx = keep * side(x, m), sy = keep * side(y, m);
      if (sx >= 0) res.push_back(x);
      if ((sx > 0 && sy < 0) || (sx < 0 && sy > 0)) {
        const auto e = common_edge(x, y, c);
        if (e.first < 0) {
          failed = true;
          continue;
        }
        res.push_back(cut_point(e.first, e.second, m));
      }
    }
    return res;
  };
  SideCut& sc = out.cut;
  std::vector<int> piece_sector;
  for (size_t t0 = 0; t0 < pr.tri.size() && !failed; ++t0) {
    const size_t first_piece = sc.pieces.size();
    double area_in = 0, area_out = 0;
    for (size_t t = 0; t < tri.size() && !failed; ++t) {
      if (tri_face[t] != static_cast<int>(t0)) continue;
      const auto& c = tri[t];
      area_in += tri_det(uv[c[0]], uv[c[1]], uv[c[2]]);
      for (int j = 0; j < k && !failed; ++j) {
        std::vector<int> poly(c.begin(), c.end());
        poly = clip(poly, j, 1, c);
        if (poly.size() >= 3) poly = clip(poly, (j + 1) % k, -1, c);
        if (poly.size() < 3) continue;
        // Fan from the vertex whose smallest triangle is largest (collinear cut points).
        const int n = static_cast<int>(poly.size());
        int apex = 0;
        double best = -kInf;
        for (int a = 0; a < n; ++a) {
          double worst = kInf;
          for (int i = 1; i + 1 < n; ++i)
            worst = std::min(worst, tri_det(uv[poly[a]], uv[poly[(a + i) % n]], uv[poly[(a + i + 1) % n]]));
          if (worst > best) best = worst, apex = a;
        }
        if (!(best > 0)) continue;  // a degenerate sliver of the sector's border: nothing inside
        for (int i = 1; i + 1 < n; ++i) {
          const std::array<int, 3> pc{poly[apex], poly[(apex + i) % n], poly[(apex + i + 1) % n]};
          area_out += tri_det(uv[pc[0]], uv[pc[1]], uv[pc[2]]);
          sc.pieces.push_back({pr.faces[t0], pc});
          piece_sector.push_back(j);
        }
      }
    }
    if (sc.pieces.size() == first_piece || std::abs(area_out - area_in) > 1e-9 * std::max(area_in, 1e-300) + 1e-15)
      failed = true;  // a face lost or doubled: the clip went wrong
  }
  if (failed) return out.with(CornerOutcome::Skipped);

  // Each piece's (u, v) in its patch: held vertices keep their wedges, points on a ray or at the
  // origin go exactly onto the square's sides, the rest through the inverse glue.
  for (size_t i = 0; i < sc.pieces.size(); ++i) {
    const int j = piece_sector[i];
    std::array<Vec2, 3> q{};
    for (int n = 0; n < 3; ++n) {
      const int l = sc.pieces[i].c[n];
      Vec2 s;
      if (l < nl && held[l] && has_wedge[static_cast<size_t>(l) * k + j]) {
        q[n] = wedge[static_cast<size_t>(l) * k + j];
        continue;
      }
      if (tag[l] == kOrigin) s = Vec2::Zero();
      else if (tag[l] == 2 * j) s = Vec2(uv[l].norm(), 0);
      else if (tag[l] == 2 * ((j + 1) % k)) s = Vec2(0, uv[l].norm());
      else s = unglue(uv[l], j);
      if (!(s.x() >= -1e-9 && s.y() >= -1e-9 && s.x() <= 1 + 1e-9 && s.y() <= 1 + 1e-9))
        return out.with(CornerOutcome::Skipped);
      q[n] = turn_square(s.cwiseMax(0.0).cwiseMin(1.0), 4 - turns[j]);
    }
    if (!(0.5 * tri_det(q[0], q[1], q[2]) > param::kZeroUvArea)) return out.with(CornerOutcome::Skipped);
    sc.piece_patch.push_back(star.patches[j]);
    sc.piece_uv.push_back(q);
  }
  // No new needles: a piece whose height is below kNeedle of its longest edge (where the energy's
  // edge matrix is floored, local_edges) would weigh far more than its area in every later pass.
  auto needle = [&](const Vec3& x0, const Vec3& x1, const Vec3& x2) {
    const double l2 = std::max({(x1 - x0).squaredNorm(), (x2 - x1).squaredNorm(), (x0 - x2).squaredNorm()});
    return (x1 - x0).cross(x2 - x0).norm() < kNeedle * l2;
  };
  for (const auto& pc : sc.pieces) {
    const auto& t = chart.mesh.faces[pc.face];
    if (!needle(base_pos[pc.c[0]], base_pos[pc.c[1]], base_pos[pc.c[2]])) continue;
    if (!needle(chart.mesh.positions[t[0]], chart.mesh.positions[t[1]], chart.mesh.positions[t[2]]))
      return out.with(CornerOutcome::Skipped);
  }
  // Keep only the new vertices that a piece uses (a crossing with a ray's continuation through
  // the origin is made while clipping, then clipped away), in the order they were made.
  std::vector<int> renumber(new_pos.size(), -1);
  for (const auto& pc : sc.pieces)
    for (int l : pc.c)
      if (l >= nl) renumber[l - nl] = 0;
  if (origin >= nl) renumber[origin - nl] = 0;
  std::vector<Vec3> used_pos;
  for (size_t i = 0; i < renumber.size(); ++i)
    if (renumber[i] == 0) {
      renumber[i] = nl + static_cast<int>(used_pos.size());
      used_pos.push_back(new_pos[i]);
    }
  for (auto& pc : sc.pieces)
    for (int& l : pc.c)
      if (l >= nl) l = renumber[l - nl];
  if (origin >= nl) origin = renumber[origin - nl];
  // Pieces of one face must be consecutive for commit_side: they are (faces in order).
  sc.vertices = std::move(pr.vertices);
  sc.new_pos = std::move(used_pos);
  out.new_corner = origin;
  sc.outcome = SideOutcome::Refined;
  return out.with(CornerOutcome::Moved);
}

}  // namespace

// `corner_sweeps` passes over B's corners (base-domain order: first met in patch order). The
// corners are grouped (in order, each into the first group whose stars share none of its
// patches), planned in parallel within a group and committed in order: the result does not depend
// on the thread count.
CornerResult move_corners(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                          const RefineOptions& options, const Context& context, const PosePull* pull) {
  CornerResult out;
  auto& chart = b.chart;
  const int np = static_cast<int>(chart.patches.size());
  std::vector<char> excluded(chart.mesh.num_vertices(), 0);
  for (int s : b.seeds)
    if (s >= 0 && s < static_cast<int>(excluded.size())) excluded[s] = 1;
  for (const auto& f : b.features)
    if (f.vertex >= 0 && f.vertex < static_cast<int>(excluded.size())) excluded[f.vertex] = 1;
  // The corners, by their first (patch, corner index), and their stars' patches (topology: fixed).
  std::vector<std::pair<int, int>> corners;
  std::vector<std::vector<int>> groups;
  {
    std::unordered_map<int, int> seen;
    for (int p = 0; p < np; ++p)
      for (int m = 0; m < 4; ++m)
        if (seen.emplace(chart.patches[p].corners[m], 0).second) corners.push_back({p, m});
    const DirectedSides sides = directed_sides(chart);
    std::vector<std::vector<char>> used;
    std::vector<std::pair<int, int>> regular;
    for (const auto& [p, m] : corners) {
      const int c = chart.patches[p].corners[m];
      if (c >= 0 && c < static_cast<int>(excluded.size()) && excluded[c]) continue;
      const auto star = corner_star(chart, sides, p, m);
      if (!star) {
        ++out.irregular;
        continue;
      }
      size_t g = 0;
      auto clash = [&](size_t gi) {
        for (int q : star->patches)
          if (used[gi][q]) return true;
        return false;
      };
      while (g < groups.size() && clash(g)) ++g;
      if (g == groups.size()) {
        groups.emplace_back();
        used.emplace_back(np, 0);
      }
      groups[g].push_back(static_cast<int>(regular.size()));
      regular.push_back({p, m});
      for (int q : star->patches) used[g][q] = 1;
    }
    corners = std::move(regular);
  }
  for (int sweep = 0; sweep < options.corner_sweeps; ++sweep) {
    int moved = 0;
    for (const auto& group : groups) {
      const std::vector<char> pinned = pinned_vertices(b);
      const DirectedSides sides = directed_sides(chart);
      const ChartIndex index(chart);
      std::vector<CornerCut> cuts(group.size());
      parallel_for(static_cast<int>(group.size()), options.threads, context, [&](int i) {
        const auto [p, m] = corners[group[i]];
        const auto star = corner_star(chart, sides, p, m);
        if (!star) {
          cuts[i].outcome = CornerOutcome::Irregular;
          return;
        }
        cuts[i] = plan_corner(chart, index, refs, *star, pinned, options, pull);
      });
      for (size_t i = 0; i < cuts.size(); ++i) {
        const auto& cc = cuts[i];
        out.steps += cc.cut.steps;
        if (cc.outcome == CornerOutcome::Moved) {
          const auto [p, m] = corners[group[i]];
          const int old_corner = chart.patches[p].corners[m];
          const int nl = static_cast<int>(cc.cut.vertices.size());
          const int new_corner =
              cc.new_corner < nl ? cc.cut.vertices[cc.new_corner] : chart.mesh.num_vertices() + (cc.new_corner - nl);
          commit_side(chart, cc.cut);
          for (auto& info : chart.patches)
            for (int& c : info.corners)
              if (c == old_corner) c = new_corner;
          for (int& v : b.base.vertices)
            if (v == old_corner) v = new_corner;
          out.added_vertices += static_cast<int>(cc.cut.new_pos.size());
          ++moved;
        }
        if (sweep == 0 && cc.outcome == CornerOutcome::Irregular) ++out.irregular;
        if (sweep == 0 && cc.outcome == CornerOutcome::Skipped) ++out.skipped;
      }
    }
    out.moved += moved;
    if (moved == 0) break;
  }
  return out;
}

}  // namespace detail

}  // namespace qs::maprefine
