#include "qs/family/pose.h"

#ifndef CGAL_EIGEN3_ENABLED
#define CGAL_EIGEN3_ENABLED  // the deformation's default sparse solver is Eigen's
#endif
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_deformation.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>
#include <numbers>
#include <queue>
#include <random>
#include <set>
#include <string>
#include <utility>

#include "qs/core/error.h"

namespace qs::family {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

using Adjacency = std::vector<std::vector<int>>;

Adjacency adjacency(const TriMesh& mesh) {
  Adjacency adj(mesh.positions.size());
  for (const Tri& t : mesh.faces)
    for (int k = 0; k < 3; ++k) {
      adj[t[k]].push_back(t[(k + 1) % 3]);
      adj[t[(k + 1) % 3]].push_back(t[k]);
    }
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  return adj;
}

// Edge-path geodesic distance from the sources (Dijkstra), up to `limit` (farther: infinity).
std::vector<double> distances(const TriMesh& mesh, const Adjacency& adj, const std::vector<int>& sources,
                              double limit = kInf) {
  std::vector<double> d(mesh.positions.size(), kInf);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (int s : sources) {
    d[s] = 0;
    queue.emplace(0.0, s);
  }
  while (!queue.empty()) {
    const auto [dv, v] = queue.top();
    queue.pop();
    if (dv > d[v]) continue;
    for (int w : adj[v]) {
      const double dw = dv + (mesh.positions[w] - mesh.positions[v]).norm();
      if (dw < d[w] && dw <= limit) {
        d[w] = dw;
        queue.emplace(dw, w);
      }
    }
  }
  return d;
}

int argmax(const std::vector<double>& d) {
  int best = 0;
  for (int v = 1; v < static_cast<int>(d.size()); ++v)
    if (d[v] != kInf && (d[best] == kInf || d[v] > d[best])) best = v;
  return best;
}

// The region {d < radius} as a limb: a connected disc (one border loop) whose border is under
// border_bound * 2 pi radius and whose area is under 30% of the mesh's. On success fills the pivot.
bool limb_region(const TriMesh& mesh, const std::vector<double>& d, double radius, double total_area, double border_bound,
                 Vec3* pivot) {
  std::vector<int> inside_faces;
  double area = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Tri& t = mesh.faces[f];
    if (d[t[0]] < radius && d[t[1]] < radius && d[t[2]] < radius) {
      inside_faces.push_back(f);
      area += face_area(mesh, f);
    }
  }
  if (inside_faces.empty() || area > 0.3 * total_area) return false;
  // Edges of the region's faces: a border edge has one of them.
  std::vector<std::pair<std::pair<int, int>, int>> edges;  // (edge, face)
  std::set<int> verts;
  for (int f : inside_faces) {
    const Tri& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      edges.push_back({{std::min(a, b), std::max(a, b)}, f});
      verts.insert(a);
    }
  }
  std::sort(edges.begin(), edges.end());
  int num_edges = 0;
  std::vector<std::pair<int, int>> border;
  // Faces joined across inner edges (union-find) to count components.
  std::vector<int> parent(inside_faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<int(int)> find = [&](int x) { return parent[x] == x ? x : parent[x] = find(parent[x]); };
  auto local = [&](int f) {
    return static_cast<int>(std::lower_bound(inside_faces.begin(), inside_faces.end(), f) - inside_faces.begin());
  };
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].first == edges[i].first) ++j;
    ++num_edges;
    if (j - i == 1) border.push_back(edges[i].first);
    for (std::size_t k = i + 1; k < j; ++k) parent[find(local(edges[k].second))] = find(local(edges[i].second));
    i = j;
  }
  int components = 0;
  for (std::size_t k = 0; k < parent.size(); ++k) components += find(static_cast<int>(k)) == static_cast<int>(k);
  const int euler = static_cast<int>(verts.size()) - num_edges + static_cast<int>(inside_faces.size());
  if (components != 1 || euler != 1 || border.empty()) return false;
  // The border against a geodesic circle of its own radius (the border's mean distance from the
  // tip, which is below `radius` by up to an edge).
  double length = 0, border_radius = 0;
  Vec3 centre = Vec3::Zero();
  for (const auto& [a, b] : border) {
    const double l = (mesh.positions[a] - mesh.positions[b]).norm();
    length += l;
    border_radius += 0.5 * l * (d[a] + d[b]);
    centre += 0.5 * l * (mesh.positions[a] + mesh.positions[b]);
  }
  if (length <= 0) return false;
  border_radius /= length;
  if (length >= border_bound * 2 * std::numbers::pi * border_radius) return false;
  *pivot = centre / length;
  return true;
}

struct ExtremityRegion {
  int tip = -1;
  double radius = 0;
  Vec3 pivot = Vec3::Zero();
  std::vector<double> d;  // geodesic distance from the tip, up to the radius
};

struct Analysis {
  Adjacency adj;
  std::vector<Extremity> extremities;
  std::vector<ExtremityRegion> limbs;  // disjoint regions, most prominent first
  std::vector<int> candidates;  // the farthest points, in the order found
};

Analysis analyse(const TriMesh& mesh, int max_count) {
  Analysis an;
  an.adj = adjacency(mesh);
  const int nv = mesh.num_vertices();
  // Farthest points: from vertex 0's farthest, each the farthest from those before.
  const int first = argmax(distances(mesh, an.adj, {0}));
  std::vector<double> nearest = distances(mesh, an.adj, {first});
  const double diameter = nearest[argmax(nearest)];
  std::vector<std::vector<double>> fields{nearest};
  an.candidates.push_back(first);
  while (an.candidates.size() < 16) {
    const int b = argmax(nearest);
    if (!(nearest[b] >= 0.12 * diameter)) break;
    an.candidates.push_back(b);
    fields.push_back(distances(mesh, an.adj, {b}));
    for (int v = 0; v < nv; ++v) nearest[v] = std::min(nearest[v], fields.back()[v]);
  }
  // The core: the candidates' geodesic median.
  int core = 0;
  double best = kInf;
  for (int v = 0; v < nv; ++v) {
    double s = 0;
    for (const auto& f : fields) s += f[v];
    if (s < best) best = s, core = v;
  }
  const std::vector<double> from_core = distances(mesh, an.adj, {core});
  // Each candidate moved uphill on the distance from the core, within a small geodesic ball.
  std::vector<int> tips;
  for (int c : an.candidates) {
    int v = c;
    for (int round = 0; round < 8; ++round) {
      const std::vector<double> ball = distances(mesh, an.adj, {v}, 0.1 * from_core[v]);
      int up = v;
      for (int w = 0; w < nv; ++w)
        if (ball[w] != kInf && (from_core[w] > from_core[up] || (from_core[w] == from_core[up] && w < up))) up = w;
      if (up == v) break;
      v = up;
    }
    bool near = false;
    for (int t : tips) near = near || distances(mesh, an.adj, {t}, 0.15 * from_core[t])[v] != kInf;
    if (!near && from_core[v] > 0.1 * diameter) tips.push_back(v);
  }
  std::sort(tips.begin(), tips.end(), [&](int a, int b) {
    return from_core[a] != from_core[b] ? from_core[a] > from_core[b] : a < b;
  });
  const double total_area = surface_area(mesh);
  // The border's bound is relaxed while fewer than 3 limbs stand out (a mesh with short legs).
  for (double border : {0.45, 0.6}) {
    an.extremities.clear();
    an.limbs.clear();
    std::vector<char> taken(nv, 0);
    for (int t : tips) {
      Extremity e;
      e.vertex = t;
      e.prominence = from_core[t];
      for (double r = 0.5 * from_core[t]; r >= 0.2 * from_core[t]; r *= 0.85) {
        std::vector<double> d = distances(mesh, an.adj, {t}, r);
        bool overlaps = false;
        for (int v = 0; v < nv && !overlaps; ++v) overlaps = d[v] < r && taken[v];
        Vec3 pivot;
        if (overlaps || !limb_region(mesh, d, r, total_area, border, &pivot)) continue;
        for (int v = 0; v < nv; ++v)
          if (d[v] < r) taken[v] = 1;
        e.limb_radius = r;
        an.limbs.push_back({t, r, pivot, std::move(d)});
        break;
      }
      an.extremities.push_back(e);
    }
    if (an.limbs.size() >= 3) break;
  }
  // Limbs first (protrusions), then the other extremities; each by prominence.
  std::stable_sort(an.extremities.begin(), an.extremities.end(),
                   [](const Extremity& a, const Extremity& b) { return (a.limb_radius > 0) > (b.limb_radius > 0); });
  if (static_cast<int>(an.extremities.size()) > max_count) an.extremities.resize(max_count);
  if (static_cast<int>(an.limbs.size()) > max_count) an.limbs.resize(max_count);
  return an;
}

double loop_length(const std::vector<std::vector<double>>& d, const std::vector<int>& order) {
  double s = 0;
  for (int k = 0; k < 4; ++k) s += d[order[k]][order[(k + 1) % 4]];
  return s;
}

// A uniform double in [0, 1) from the generator's bits (the same on every standard library).
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

Eigen::Matrix3d rotation(const Vec3& axis, double angle_deg) {
  return Eigen::AngleAxisd(angle_deg * std::numbers::pi / 180, axis).toRotationMatrix();
}

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using SM = CGAL::Surface_mesh<K::Point_3>;

SM to_surface_mesh(const TriMesh& mesh) {
  SM sm;
  for (const Vec3& p : mesh.positions) sm.add_vertex(K::Point_3(p.x(), p.y(), p.z()));
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Tri& t = mesh.faces[f];
    if (sm.add_face(SM::Vertex_index(t[0]), SM::Vertex_index(t[1]), SM::Vertex_index(t[2])) == SM::null_face())
      throw InvalidInput("pose: face " + std::to_string(f) + " cannot be added (the mesh is not a validated manifold)");
  }
  return sm;
}

std::set<std::pair<int, int>> self_intersections(const TriMesh& mesh) {
  const SM sm = to_surface_mesh(mesh);
  std::vector<std::pair<SM::Face_index, SM::Face_index>> pairs;
  CGAL::Polygon_mesh_processing::self_intersections(faces(sm), sm, std::back_inserter(pairs));
  std::set<std::pair<int, int>> out;
  for (const auto& [a, b] : pairs) {
    const int x = static_cast<int>(a), y = static_cast<int>(b);
    out.insert({std::min(x, y), std::max(x, y)});
  }
  return out;
}

Vec3 face_normal(const std::vector<Vec3>& p, const Tri& t) {
  return (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
}

}  // namespace

std::vector<int> folded_faces(const TriMesh& rest, const TriMesh& posed) {
  std::vector<std::pair<std::pair<int, int>, int>> edges;
  for (int f = 0; f < rest.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = rest.faces[f][k], b = rest.faces[f][(k + 1) % 3];
      edges.push_back({{std::min(a, b), std::max(a, b)}, f});
    }
  std::sort(edges.begin(), edges.end());
  std::vector<char> bad(rest.faces.size(), 0);
  for (int f = 0; f < rest.num_faces(); ++f) {
    const double a0 = face_normal(rest.positions, rest.faces[f]).norm();
    const double a1 = face_normal(posed.positions, rest.faces[f]).norm();
    if (a1 < 1e-3 * a0) bad[f] = 1;
  }
  for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
    if (edges[i].first != edges[i + 1].first) continue;
    const int f = edges[i].second, g = edges[i + 1].second;
    const Vec3 n0 = face_normal(rest.positions, rest.faces[f]).normalized();
    const Vec3 m0 = face_normal(rest.positions, rest.faces[g]).normalized();
    const Vec3 n1 = face_normal(posed.positions, rest.faces[f]).normalized();
    const Vec3 m1 = face_normal(posed.positions, rest.faces[g]).normalized();
    if (n0.dot(m0) > 0.5 && !(n1.dot(m1) > 0)) bad[f] = bad[g] = 1;
  }
  std::vector<int> out;
  for (int f = 0; f < rest.num_faces(); ++f)
    if (bad[f]) out.push_back(f);
  return out;
}

std::vector<Extremity> find_extremities(const TriMesh& mesh, int max_count) {
  if (max_count < 1) throw InvalidInput("find_extremities: max_count must be at least 1");
  return analyse(mesh, max_count).extremities;
}

std::vector<int> shortest_loop_order(const TriMesh& mesh, const std::vector<int>& seeds) {
  if (seeds.size() != 4) throw InvalidInput("shortest_loop_order: 4 seeds expected");
  const Adjacency adj = adjacency(mesh);
  std::vector<std::vector<double>> d(4, std::vector<double>(4, 0));
  for (int i = 0; i < 4; ++i) {
    const std::vector<double> di = distances(mesh, adj, {seeds[i]});
    for (int j = 0; j < 4; ++j) d[i][j] = di[seeds[j]];
  }
  std::vector<int> best{0, 1, 2, 3};
  for (const std::vector<int>& o : {std::vector<int>{0, 1, 3, 2}, std::vector<int>{0, 2, 1, 3}})
    if (loop_length(d, o) < loop_length(d, best) - 1e-12 * loop_length(d, best)) best = o;
  return {seeds[best[0]], seeds[best[1]], seeds[best[2]], seeds[best[3]]};
}

PoseLandmarks choose_landmarks(const TriMesh& mesh) {
  const Analysis an = analyse(mesh, 10);
  std::vector<int> chosen;
  for (const Extremity& e : an.extremities) chosen.push_back(e.vertex);
  // Too few extremities: geodesic farthest points from those chosen.
  std::vector<double> nearest = distances(mesh, an.adj, chosen.empty() ? std::vector<int>{an.candidates[0]} : chosen);
  if (chosen.empty()) chosen.push_back(an.candidates[0]);
  while (chosen.size() < 6) {
    const int b = argmax(nearest);
    if (!(nearest[b] > 0)) throw SolverError("pose: the mesh is too small for 6 landmarks");
    chosen.push_back(b);
    const std::vector<double> db = distances(mesh, an.adj, {b});
    for (std::size_t v = 0; v < nearest.size(); ++v) nearest[v] = std::min(nearest[v], db[v]);
  }
  if (chosen.size() > 10) chosen.resize(10);
  PoseLandmarks lm;
  lm.seeds = shortest_loop_order(mesh, {chosen[0], chosen[1], chosen[2], chosen[3]});
  for (std::size_t k = 4; k < chosen.size(); ++k) lm.features.push_back({"tip" + std::to_string(k), chosen[k]});
  return lm;
}

Pose pose_mesh(const TriMesh& mesh, const PoseOptions& options, const Context& context) {
  if (options.limbs < 0) throw InvalidInput("pose: limbs = " + std::to_string(options.limbs) + " (expected >= 0)");
  if (!(options.min_angle_deg >= 5 && options.min_angle_deg <= options.max_angle_deg && options.max_angle_deg <= 120))
    throw InvalidInput("pose: angles " + std::to_string(options.min_angle_deg) + ".." +
                       std::to_string(options.max_angle_deg) + " (expected 5 <= min <= max <= 120)");
  if (!(options.smallest_angle_deg > 0 && options.smallest_angle_deg <= options.min_angle_deg))
    throw InvalidInput("pose: the smallest angle must be in (0, min]");
  context.report("pose", 0);
  Analysis an = analyse(mesh, 8);
  Pose pose;
  pose.limbs_found = static_cast<int>(an.limbs.size());
  if (an.limbs.empty()) throw SolverError("pose: no limb found on the mesh (no extremity stands out as a protrusion)");
  std::mt19937_64 rng(options.seed * 0x9E3779B97F4A7C15ull + 0x632BE59BD9B4E019ull);
  // Which limbs, in a seeded order, then each limb's axis and angle.
  std::vector<int> order(an.limbs.size());
  std::iota(order.begin(), order.end(), 0);
  for (std::size_t i = order.size(); i > 1; --i) std::swap(order[i - 1], order[rng() % i]);
  if (options.limbs > 0 && options.limbs < static_cast<int>(order.size())) order.resize(options.limbs);
  std::sort(order.begin(), order.end());
  std::vector<PosedLimb> limbs;
  for (int k : order) {
    const ExtremityRegion& l = an.limbs[k];
    PosedLimb p;
    p.tip = l.tip;
    p.radius = l.radius;
    p.pivot = l.pivot;
    Vec3 dir = mesh.positions[l.tip] - l.pivot;
    if (dir.norm() <= 0) dir = Vec3::UnitZ();
    dir.normalize();
    const bool twist = options.kind == PoseKind::Twist || (options.kind == PoseKind::Mixed && rng() % 4 == 0);
    Vec3 u(uniform(rng) - 0.5, uniform(rng) - 0.5, uniform(rng) - 0.5);
    u -= u.dot(dir) * dir;
    if (u.norm() < 1e-6) u = dir.unitOrthogonal();
    p.twist = twist;
    p.axis = twist ? dir : Vec3(u.normalized());
    const double a = options.min_angle_deg + (options.max_angle_deg - options.min_angle_deg) * uniform(rng);
    p.angle_deg = rng() % 2 ? a : -a;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (l.d[v] < l.radius) p.region.push_back(v);
      if (l.d[v] < 0.5 * l.radius) p.handle.push_back(v);
    }
    limbs.push_back(std::move(p));
  }
  std::vector<int> limb_of(mesh.num_vertices(), -1);
  for (std::size_t k = 0; k < limbs.size(); ++k)
    for (int v : limbs[k].region) limb_of[v] = static_cast<int>(k);
  const std::set<std::pair<int, int>> before = self_intersections(mesh);
  pose.input_self_intersections = static_cast<int>(before.size());
  // Faces that already cross the surface in the input (touching fingers, say) may cross elsewhere
  // once moved: only crossings between other faces count.
  std::vector<char> crossing_before(mesh.faces.size(), 0);
  for (const auto& [f, g] : before) crossing_before[f] = crossing_before[g] = 1;
  std::vector<int> tries(limbs.size(), 0);
  std::vector<char> active(limbs.size(), 1);
  for (int attempt = 0; attempt < 12; ++attempt) {
    context.check_cancel();
    SM sm = to_surface_mesh(mesh);
    CGAL::Surface_mesh_deformation<SM> deform(sm);
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      if (!active[k]) continue;
      for (int v : limbs[k].region) deform.insert_roi_vertex(SM::Vertex_index(v));
      for (int v : limbs[k].handle) deform.insert_control_vertex(SM::Vertex_index(v));
    }
    if (!deform.preprocess()) throw SolverError("pose: the deformation's linear system cannot be factorized");
    // In three steps, each from the last one's result: a large rotation in one step starts from
    // the rest pose and converges to a worse minimum.
    constexpr int kSteps = 3;
    for (int step = 1; step <= kSteps; ++step) {
      for (std::size_t k = 0; k < limbs.size(); ++k) {
        if (!active[k]) continue;
        const Eigen::Matrix3d r = rotation(limbs[k].axis, limbs[k].angle_deg * step / kSteps);
        for (int v : limbs[k].handle) {
          const Vec3 q = limbs[k].pivot + r * (mesh.positions[v] - limbs[k].pivot);
          deform.set_target_position(SM::Vertex_index(v), K::Point_3(q.x(), q.y(), q.z()));
        }
      }
      deform.deform(50, 1e-6);
    }
    TriMesh out = mesh;
    for (int v = 0; v < mesh.num_vertices(); ++v) {
      if (limb_of[v] < 0 || !active[limb_of[v]]) continue;
      const auto& q = sm.point(SM::Vertex_index(v));
      out.positions[v] = Vec3(q.x(), q.y(), q.z());
    }
    // Which limbs fold a face or cross the surface.
    std::vector<char> failed(limbs.size(), 0);
    auto blame = [&](int f) {
      for (int c : mesh.faces[f])
        if (limb_of[c] >= 0) failed[limb_of[c]] = 1;
    };
    for (int f : folded_faces(mesh, out)) blame(f);
    for (const auto& pr : self_intersections(out))
      if (!crossing_before[pr.first] && !crossing_before[pr.second]) blame(pr.first), blame(pr.second);
    bool any = false;
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      if (!failed[k] || !active[k]) continue;
      any = true;
      // First the other way round, then smaller.
      if (tries[k]++ == 0) {
        limbs[k].angle_deg = -limbs[k].angle_deg;
      } else {
        limbs[k].angle_deg *= 0.75;
        if (std::abs(limbs[k].angle_deg) < options.smallest_angle_deg) active[k] = 0;
      }
    }
    context.report("pose", (attempt + 1) / 12.0);
    if (any) continue;
    for (std::size_t k = 0; k < limbs.size(); ++k) {
      if (!active[k]) continue;
      const Eigen::Matrix3d r = rotation(limbs[k].axis, limbs[k].angle_deg);
      for (int v : limbs[k].handle)
        pose.max_handle_error = std::max(
            pose.max_handle_error, (out.positions[v] - (limbs[k].pivot + r * (mesh.positions[v] - limbs[k].pivot))).norm());
      pose.limbs.push_back(limbs[k]);
    }
    pose.limbs_dropped = static_cast<int>(limbs.size() - pose.limbs.size());
    if (pose.limbs.empty()) throw SolverError("pose: no limb could be posed without folding or crossing the surface");
    pose.mesh = std::move(out);
    context.report("pose", 1);
    return pose;
  }
  throw SolverError("pose: the limbs still fold or cross the surface after 12 attempts");
}

}  // namespace qs::family
