// The automatic seed rules of the seed loop (choose_seeds and its candidates). The rule in full:
// docs/algorithms.md.

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <exception>
#include <functional>
#include <future>
#include <optional>
#include <set>
#include <string>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/dissect/seed_loop.h"
#include "qs/dissect/seed_routing_detail.h"

namespace qs::dissect {

using namespace routing;

namespace {

/// choose_seeds routes its candidates on several threads from this many faces.
constexpr int kParallelRouteFaces = 20000;

/// Vertex areas (a third of each incident face's area); all 1 for used vertices when the mesh has
/// no area. Unused vertices weigh 0 and are flagged in `used`.
std::vector<double> vertex_weights(const TriMesh& mesh, std::vector<char>& used) {
  const int nv = mesh.num_vertices();
  std::vector<double> w(nv, 0.0);
  used.assign(nv, 0);
  double total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Tri& t = mesh.faces[f];
    for (int v : t)
      if (v < 0 || v >= nv)
        throw InvalidInput("choose_seeds: face " + std::to_string(f) + " has vertex index " +
                           std::to_string(v) + " outside [0, " + std::to_string(nv) + ")");
    const Vec3& p0 = mesh.positions[t[0]];
    const double a = (mesh.positions[t[1]] - p0).cross(mesh.positions[t[2]] - p0).norm() / 6.0;
    for (int v : t) {
      w[v] += a;
      used[v] = 1;
    }
    total += 3 * a;
  }
  if (!(total > 0) || !std::isfinite(total))
    for (int v = 0; v < nv; ++v) w[v] = used[v] ? 1.0 : 0.0;
  return w;
}

struct Axes {
  Vec3 centroid = Vec3::Zero();
  Vec3 e1 = Vec3::UnitX(), e2 = Vec3::UnitY();
};

Axes principal_axes(const TriMesh& mesh, const std::vector<double>& w) {
  const int nv = mesh.num_vertices();
  double total = 0;
  Axes axes;
  for (int v = 0; v < nv; ++v) {
    total += w[v];
    axes.centroid += w[v] * mesh.positions[v];
  }
  axes.centroid /= total;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int v = 0; v < nv; ++v) {
    const Vec3 d = mesh.positions[v] - axes.centroid;
    cov += w[v] * d * d.transpose();
  }
  cov /= total;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  auto fix_sign = [&](Vec3 e, double variance) {
    double m3 = 0;
    for (int v = 0; v < nv; ++v) {
      const double x = (mesh.positions[v] - axes.centroid).dot(e);
      m3 += w[v] * x * x * x;
    }
    m3 /= total;
    const double sigma = std::sqrt(std::max(variance, 0.0));
    if (std::abs(m3) > 1e-6 * sigma * sigma * sigma) {
      if (m3 < 0) e = -e;
    } else {
      int k = 0;
      for (int j = 1; j < 3; ++j)
        if (std::abs(e[j]) > std::abs(e[k])) k = j;
      if (e[k] < 0) e = -e;
    }
    return e;
  };
  axes.e1 = fix_sign(solver.eigenvectors().col(2), solver.eigenvalues()[2]);
  axes.e2 = fix_sign(solver.eigenvectors().col(1), solver.eigenvalues()[1]);
  return axes;
}

/// The vertex with the largest sign * value among used ones not yet taken, lowest id on ties.
int extreme(const std::vector<double>& value, double sign, const std::vector<char>& used,
            const std::array<int, 4>& taken) {
  int best = -1;
  for (int v = 0; v < static_cast<int>(value.size()); ++v) {
    if (!used[v] || std::find(taken.begin(), taken.end(), v) != taken.end()) continue;
    if (best < 0 || sign * value[v] > sign * value[best]) best = v;
  }
  return best;
}

/// The nearest vertex of the first face hit by the ray from `origin` along `dir` (smallest
/// positive distance, Moller-Trumbore), or -1 when the ray hits nothing.
int ray_seed(const TriMesh& mesh, const Vec3& origin, const Vec3& dir, const std::array<int, 4>& taken) {
  double best_t = std::numeric_limits<double>::infinity();
  Vec3 hit = Vec3::Zero();
  int best_f = -1;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Vec3& a = mesh.positions[mesh.faces[f][0]];
    const Vec3 e1 = mesh.positions[mesh.faces[f][1]] - a, e2 = mesh.positions[mesh.faces[f][2]] - a;
    const Vec3 p = dir.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) continue;
    const Vec3 t0 = origin - a;
    const double u = t0.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Vec3 q = t0.cross(e1);
    const double v = dir.dot(q) / det;
    if (v < 0 || u + v > 1) continue;
    const double t = e2.dot(q) / det;
    if (t > 0 && t < best_t) {
      best_t = t;
      best_f = f;
      hit = origin + t * dir;
    }
  }
  if (best_f < 0) return -1;
  int best = -1;
  for (int v : mesh.faces[best_f])
    if (std::find(taken.begin(), taken.end(), v) == taken.end() &&
        (best < 0 || (mesh.positions[v] - hit).norm() < (mesh.positions[best] - hit).norm()))
      best = v;
  return best;
}

/// The extreme vertices along +a, +b, -a, -b (a, b: values per vertex) among the used ones, each
/// other than those before it.
std::array<int, 4> extremes(const std::vector<double>& a, const std::vector<double>& b, const std::vector<char>& used) {
  std::array<int, 4> s{-1, -1, -1, -1};
  s[0] = extreme(a, +1, used, s);
  s[1] = extreme(b, +1, used, s);
  s[2] = extreme(a, -1, used, s);
  s[3] = extreme(b, -1, used, s);
  return s;
}

std::array<int, 4> extreme_seeds(const TriMesh& mesh, const std::vector<char>& used, const Axes& axes) {
  const int nv = mesh.num_vertices();
  std::vector<double> p1(nv), p2(nv);
  for (int v = 0; v < nv; ++v) {
    const Vec3 d = mesh.positions[v] - axes.centroid;
    p1[v] = d.dot(axes.e1);
    p2[v] = d.dot(axes.e2);
  }
  return extremes(p1, p2, used);
}

std::array<int, 4> pca_seeds(const TriMesh& mesh, const std::vector<char>& used,
                             const Axes& axes) {
  // Where the rays from the centroid along +e1, +e2, -e1, -e2 first meet the surface: a belt
  // around the body, not out to the tips of protrusions (a seed at a hoof makes two paths run up
  // and down the same leg side by side). The extreme vertex when a ray meets nothing.
  std::array<int, 4> s{-1, -1, -1, -1};
  const std::array<Vec3, 4> dirs = {axes.e1, axes.e2, -axes.e1, -axes.e2};
  for (int i = 0; i < 4; ++i) s[i] = ray_seed(mesh, axes.centroid, dirs[i], s);
  if (std::find(s.begin(), s.end(), -1) != s.end()) {
    const std::array<int, 4> ext = extreme_seeds(mesh, used, axes);
    for (int i = 0; i < 4; ++i)
      if (s[i] < 0) s[i] = std::find(s.begin(), s.end(), ext[i]) == s.end() ? ext[i] : -1;
  }
  return s;
}

/// A slab candidate (docs/algorithms.md, the seed rule): the extreme vertices along +a, +b, -a,
/// -b among those within a thin slab around the plane through the centroid normal to n (half-width
/// kSlabWidth of the extent along n, doubled until the slab holds 4 vertices): a belt around the
/// body across n even where the centroid lies outside the body and the rays start elsewhere.
constexpr double kSlabWidth = 0.01;
/// A slab candidate replaces the best of the others only when its score is this many times theirs.
constexpr double kSlabMargin = 1.5;

std::array<int, 4> slab_seeds(const TriMesh& mesh, const std::vector<char>& used, const Vec3& centroid,
                              const Vec3& n, const Vec3& a, const Vec3& b) {
  const int nv = mesh.num_vertices();
  std::vector<double> pn(nv), pa(nv), pb(nv);
  double lo = INFINITY, hi = -INFINITY;
  for (int v = 0; v < nv; ++v) {
    const Vec3 d = mesh.positions[v] - centroid;
    pn[v] = d.dot(n), pa[v] = d.dot(a), pb[v] = d.dot(b);
    if (used[v]) lo = std::min(lo, pn[v]), hi = std::max(hi, pn[v]);
  }
  std::vector<char> in(nv, 0);
  for (double h = kSlabWidth * (hi - lo); h <= 2 * (hi - lo); h *= 2) {
    int count = 0;
    for (int v = 0; v < nv; ++v) count += in[v] = used[v] && std::abs(pn[v]) <= h;
    if (count >= 4) break;
  }
  return extremes(pa, pb, in);
}

/// The geodesic candidate (choose_seeds_farthest).
std::array<int, 4> farthest_seeds(const TriMesh& mesh, Dijkstra& dijkstra,
                                  const std::vector<char>& used, const Axes& axes) {
  const int nv = mesh.num_vertices();
  int c = -1;
  for (int v = 0; v < nv; ++v)
    if (used[v] && (c < 0 || (mesh.positions[v] - axes.centroid).squaredNorm() <
                                 (mesh.positions[c] - axes.centroid).squaredNorm()))
      c = v;
  auto farthest = [&](const std::vector<double>& score, const std::array<int, 4>& taken) {
    int best = -1;
    for (int v = 0; v < nv; ++v) {
      if (!used[v] || score[v] == kInf || std::find(taken.begin(), taken.end(), v) != taken.end())
        continue;
      if (best < 0 || score[v] > score[best]) best = v;
    }
    return best;
  };
  // -1 (no vertex with a finite distance left) must never reach the distance code.
  auto found = [](int v) {
    if (v < 0)
      throw InvalidInput("choose_seeds: fewer than 4 vertices are reachable at a finite distance; "
                         "give the four seeds by hand");
    return v;
  };
  std::array<int, 4> s{-1, -1, -1, -1};
  found(c);
  s[0] = found(farthest(dijkstra.all_distances(c), s));
  const std::vector<double> d0 = dijkstra.all_distances(s[0]);
  s[2] = found(farthest(d0, s));
  const std::vector<double> d2 = dijkstra.all_distances(s[2]);
  std::vector<double> m(nv);
  for (int v = 0; v < nv; ++v) m[v] = std::min(d0[v], d2[v]);
  s[1] = found(farthest(m, s));
  const std::vector<double> d1 = dijkstra.all_distances(s[1]);
  for (int v = 0; v < nv; ++v) m[v] = std::min(m[v], d1[v]);
  s[3] = found(farthest(m, s));
  // Counter-clockwise around +e3: the quadrilateral projected on (e1, e2) has positive area.
  double area = 0;
  for (int i = 0; i < 4; ++i) {
    const Vec3 a = mesh.positions[s[i]] - axes.centroid;
    const Vec3 b = mesh.positions[s[(i + 1) % 4]] - axes.centroid;
    area += a.dot(axes.e1) * b.dot(axes.e2) - a.dot(axes.e2) * b.dot(axes.e1);
  }
  if (area < 0) std::swap(s[1], s[3]);
  return s;
}

std::string seeds_text(const std::array<int, 4>& s) {
  return std::to_string(s[0]) + ", " + std::to_string(s[1]) + ", " + std::to_string(s[2]) + ", " +
         std::to_string(s[3]);
}

// How a candidate seed loop cuts the surface: the area fraction of its smaller side and its
// length relative to sqrt(total area) (a belt around a sphere scores sqrt(pi) = 1.77; a loop that
// runs up a limb and back down scores far more).
struct LoopScore {
  double fraction = 0;
  double length = 0;
  double value() const { return fraction / std::max(length, 1e-12); }
};

// Routes one candidate seed set, or returns nullopt (with the reason appended to `why`) when the
// seeds are not 4 distinct vertices or do not route.
std::optional<LoopScore> route_score(const TriMesh& mesh, const Graph& g, Dijkstra& dijkstra,
                                     const std::vector<double>& face_area, const std::string& name,
                                     const std::array<int, 4>& seeds, std::string& why) {
  const bool distinct = std::set<int>(seeds.begin(), seeds.end()).size() == 4 &&
                        std::none_of(seeds.begin(), seeds.end(), [](int v) { return v < 0; });
  const Attempt a = distinct ? try_route(mesh, g, dijkstra, seeds, {}) : Attempt{};
  if (!a.ok) {
    why += (why.empty() ? "" : "; ") + name + " (vertices " + seeds_text(seeds) +
           "): " + (distinct ? a.why : "not 4 distinct vertices");
    return std::nullopt;
  }
  double side0 = 0, total = 0;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    total += face_area[f];
    if (a.labels[f] == 0) side0 += face_area[f];
  }
  LoopScore score;
  score.fraction = std::min(side0, total - side0) / std::max(total, 1e-300);
  for (const auto& p : a.loop.paths) score.length += path_length(mesh, p);
  score.length /= std::sqrt(std::max(total, 1e-300));
  return score;
}

std::vector<double> face_areas(const TriMesh& mesh) {
  std::vector<double> area(mesh.num_faces());
  for (int f = 0; f < mesh.num_faces(); ++f) {
    const Tri& t = mesh.faces[f];
    const Vec3& a = mesh.positions[t[0]];
    area[f] = 0.5 * (mesh.positions[t[1]] - a).cross(mesh.positions[t[2]] - a).norm();
  }
  return area;
}

// The principal axes of the area-weighted vertices, with `used` marking the vertices faces use.
// \throws InvalidInput when fewer than 4 vertices are used.
Axes checked_axes(const TriMesh& mesh, std::vector<char>& used) {
  const std::vector<double> w = vertex_weights(mesh, used);
  if (std::count(used.begin(), used.end(), 1) < 4)
    throw InvalidInput("choose_seeds: the mesh has fewer than 4 vertices used by faces");
  return principal_axes(mesh, w);
}

[[noreturn]] void no_routable_seeds(const std::string& why) {
  throw InvalidInput("choose_seeds: no rule gives a routable seed loop: " + why + "; give the four seeds by hand");
}

}  // namespace

std::array<int, 4> first_routable_seeds(const TriMesh& mesh,
                                        const std::vector<std::pair<std::string, std::array<int, 4>>>& candidates) {
  const Graph g = build_graph(mesh);
  Dijkstra dijkstra(g);
  const std::vector<double> area = face_areas(mesh);
  std::string why;
  for (const auto& [name, seeds] : candidates) {
    check_seeds(mesh, seeds);
    if (route_score(mesh, g, dijkstra, area, name, seeds, why)) return seeds;
  }
  no_routable_seeds(why);
}

std::array<int, 4> choose_seeds(const TriMesh& mesh, const Context& context) {
  Graph g;
  return routing::choose_seeds(mesh, context, g);
}

std::array<int, 4> routing::choose_seeds(const TriMesh& mesh, const Context& context, Graph& g) {
  // The routing graph is built beside the axes and the face areas on large meshes (the axes'
  // error, when both fail, is the one thrown, as in one thread).
  const bool beside =
      mesh.num_faces() >= kParallelRouteFaces && thread_count(0, context) > 1 && !inside_parallel_loop();
  std::future<Graph> graph;
  if (beside) graph = std::async(std::launch::async, [&] { return build_graph(mesh); });
  std::vector<char> used;
  const Axes axes = checked_axes(mesh, used);
  const std::vector<double> area = face_areas(mesh);
  g = beside ? graph.get() : build_graph(mesh);
  // Candidates: ray belts in the three principal planes, each also turned by 45 degrees about the
  // plane's normal, then the principal-axis extremes and the geodesically farthest vertices. The
  // loop with the best area fraction per length wins among those enclosing at least 5% of the
  // area (else the most even one): a short belt that cuts the shape in two sizable halves.
  const Vec3 e3 = axes.e1.cross(axes.e2);
  std::vector<std::pair<std::string, std::function<std::array<int, 4>(Dijkstra&)>>> rules;
  const std::array<std::pair<Vec3, Vec3>, 3> planes = {
      std::pair{axes.e1, axes.e2}, std::pair{axes.e1, e3}, std::pair{axes.e2, e3}};
  const char* plane_names[] = {"e1-e2", "e1-e3", "e2-e3"};
  for (int pl = 0; pl < 3; ++pl)
    for (int turn = 0; turn < 2; ++turn) {
      Axes a = axes;
      const double c = std::cos(turn * M_PI / 4), s = std::sin(turn * M_PI / 4);
      a.e1 = c * planes[pl].first + s * planes[pl].second;
      a.e2 = -s * planes[pl].first + c * planes[pl].second;
      rules.emplace_back(std::string("the ") + plane_names[pl] + " rays" + (turn ? " turned 45 degrees" : ""),
                         [&, a](Dijkstra&) { return pca_seeds(mesh, used, a); });
    }
  rules.emplace_back("the principal-axis extremes", [&](Dijkstra&) { return extreme_seeds(mesh, used, axes); });
  const size_t farthest = rules.size();
  rules.emplace_back("the geodesically farthest vertices",
                     [&](Dijkstra& d) { return farthest_seeds(mesh, d, used, axes); });
  const size_t others = rules.size();
  for (int turn = 0; turn < 2; ++turn) {
    const double c = std::cos(turn * M_PI / 4), s = std::sin(turn * M_PI / 4);
    const Vec3 b = c * axes.e2 + s * e3, n = -s * axes.e2 + c * e3;
    rules.emplace_back(std::string("the e1 slab extremes") + (turn ? " turned 45 degrees" : ""),
                       [&, b, n](Dijkstra&) { return slab_seeds(mesh, used, axes.centroid, axes.e1, b, n); });
  }
  // Each rule's seeds are found and routed on their own (one search state each), on the
  // context's threads; the farthest vertices, the slowest rule, first.
  std::vector<size_t> order{farthest};
  for (size_t i = 0; i < rules.size(); ++i)
    if (i != farthest) order.push_back(i);
  std::vector<std::array<int, 4>> seeds(rules.size());
  std::vector<std::optional<LoopScore>> scores(rules.size());
  std::vector<std::string> failures(rules.size());
  std::vector<std::exception_ptr> errors(rules.size());
  parallel_for(rules.size(), mesh.num_faces() >= kParallelRouteFaces ? 0 : 1, context, [&](size_t k) {
    const size_t i = order[k];
    try {
      Dijkstra dijkstra(g);
      seeds[i] = rules[i].second(dijkstra);
      scores[i] = route_score(mesh, g, dijkstra, area, rules[i].first, seeds[i], failures[i]);
    } catch (...) {
      errors[i] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors)  // the first rule's error, as one after the other
    if (e) std::rethrow_exception(e);
  std::string why;
  for (const std::string& f : failures)
    if (!f.empty()) why += (why.empty() ? "" : "; ") + f;
  int best = -1;
  LoopScore best_score;
  bool best_ok = false;
  for (size_t i = 0; i < rules.size(); ++i) {
    const auto& score = scores[i];
    if (!score) continue;
    const bool ok = score->fraction >= 0.05;
    // A slab candidate must beat the others clearly (kSlabMargin): where the rays give a good belt
    // the slab's is about as good, and the rays' choice is kept.
    const double margin = i >= others && best >= 0 && static_cast<size_t>(best) < others ? kSlabMargin : 1.0;
    const bool better = best < 0 || (ok && !best_ok) ||
                        (ok == best_ok && (ok ? score->value() > margin * best_score.value() + 1e-12
                                              : score->fraction > best_score.fraction + 1e-12));
    if (better) {
      best = static_cast<int>(i);
      best_score = *score;
      best_ok = ok;
    }
  }
  if (best < 0) no_routable_seeds(why);
  return seeds[best];
}

std::array<int, 4> choose_seeds_farthest(const TriMesh& mesh) {
  std::vector<char> used;
  const Axes axes = checked_axes(mesh, used);
  const Graph g = build_graph(mesh);
  Dijkstra dijkstra(g);
  return farthest_seeds(mesh, dijkstra, used, axes);
}

}  // namespace qs::dissect
