// Foldover-free warp of the unit square by triangulation over time (Fujimura & Makarov 1998),
// kept Delaunay while features move. CGAL builds the initial warp mesh; the kinetic flips run on a
// small triangle structure of our own.

#include "qs/warp/warp.h"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/core/problem_list.h"

namespace qs::warp {
namespace {

/// Points up to this far outside the square are clamped onto it; farther ones are rejected.
constexpr double kOutsideTolerance = 1e-12;
/// A barycentric weight below this is set to exactly 0 (and the others renormalized): points on
/// an edge stay exactly on it, points on a vertex follow it exactly.
constexpr double kTinyWeight = 1e-14;
/// Events up to this far past the end of a straight leg (in units of the leg) are processed too,
/// so a feature never comes to rest almost on an edge of the warp mesh.
constexpr double kEndTolerance = 1e-9;
/// A flip is done only where all triangles involved have at least this doubled signed area.
constexpr double kMinArea2 = 1e-15;
/// Relative rounding allowance of the incircle test (nearly cocircular quads are left alone).
constexpr double kIncircleTolerance = 1e-10;
/// Delaunay events closer in time than this (in units of one straight leg) count as simultaneous.
constexpr double kSameTime = 1e-12;
constexpr int kCorners = 4;
const std::array<Vec2, kCorners> kCornerPos = {Vec2(0, 0), Vec2(1, 0), Vec2(1, 1), Vec2(0, 1)};

/// Twice the signed area of (a, b, c): > 0 when counter-clockwise.
double orient(const Vec2& a, const Vec2& b, const Vec2& c) { return cross2(b - a, c - a); }

/// > 0 when d lies inside the circle through the counter-clockwise triangle (a, b, c).
double incircle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const Vec2 ad = a - d, bd = b - d, cd = c - d;
  return ad.squaredNorm() * cross2(bd, cd) + bd.squaredNorm() * cross2(cd, ad) + cd.squaredNorm() * cross2(ad, bd);
}

double border_distance(const Vec2& p) {
  return std::min(std::min(p.x(), 1 - p.x()), std::min(p.y(), 1 - p.y()));
}

std::string str(const Vec2& p) {
  std::ostringstream s;
  s.precision(10);
  s << '(' << p.x() << ", " << p.y() << ')';
  return s.str();
}


/// Pairs (i, j), i < j, of points closer than d to each other (sweep along x), sorted.
std::vector<std::pair<int, int>> close_pairs(const std::vector<Vec2>& p, double d) {
  std::vector<int> order(p.size());
  for (std::size_t i = 0; i < p.size(); ++i) order[i] = static_cast<int>(i);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return p[a].x() != p[b].x() ? p[a].x() < p[b].x() : a < b;
  });
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (std::size_t j = i + 1; j < order.size() && p[order[j]].x() - p[order[i]].x() < d; ++j) {
      if ((p[order[j]] - p[order[i]]).norm() < d)
        pairs.emplace_back(std::min(order[i], order[j]), std::max(order[i], order[j]));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

void check_features(const std::vector<Vec2>& p, const std::string& name, double m,
                    std::vector<std::string>& problems) {
  ProblemList nonfinite(name + "s with a non-finite coordinate");
  ProblemList border(name + "s closer than min_feature_distance (" + std::to_string(m) +
                     ") to the square's border or outside it");
  bool all_finite = true;
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (!p[k].allFinite()) {
      nonfinite.add(std::to_string(k));
      all_finite = false;
    } else if (border_distance(p[k]) < m) {
      border.add(std::to_string(k) + " at " + str(p[k]));
    }
  }
  nonfinite.append_to(problems);
  border.append_to(problems);
  if (!all_finite) return;
  ProblemList close(name + "s closer than min_feature_distance (" + std::to_string(m) +
                    ") to each other");
  for (const auto& [i, j] : close_pairs(p, m))
    close.add(std::to_string(i) + " at " + str(p[i]) + " and " + std::to_string(j) + " at " + str(p[j]));
  close.append_to(problems);
}

void validate(const std::vector<Vec2>& features, const std::vector<Vec2>& targets,
              const std::vector<Vec2>& points, const WarpOptions& options) {
  std::vector<std::string> problems;
  const double m = options.min_feature_distance;
  if (!(m > 0 && m < 0.25))
    problems.push_back("options.min_feature_distance = " + std::to_string(m) + " is not in (0, 0.25)");
  if (options.rounds < 1)
    problems.push_back("options.rounds = " + std::to_string(options.rounds) + " is not >= 1");
  if (options.max_events < 0)
    problems.push_back("options.max_events = " + std::to_string(options.max_events) + " is negative");
  if (features.size() != targets.size())
    problems.push_back(std::to_string(features.size()) + " features but " + std::to_string(targets.size()) +
                       " targets (one target per feature)");
  if (m > 0 && m < 0.25) {
    check_features(features, "feature", m, problems);
    check_features(targets, "target", m, problems);
  }
  ProblemList outside("points outside the unit square (by more than 1e-12) or not finite");
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vec2& p = points[i];
    if (!p.allFinite() || p.x() < -kOutsideTolerance || p.x() > 1 + kOutsideTolerance ||
        p.y() < -kOutsideTolerance || p.y() > 1 + kOutsideTolerance)
      outside.add(std::to_string(i) + " at " + str(p));
  }
  outside.append_to(problems);
  if (problems.empty()) return;
  std::ostringstream s;
  s << "warp_square: ";
  for (std::size_t i = 0; i < problems.size(); ++i) s << (i ? "; " : "") << problems[i];
  throw InvalidInput(s.str());
}

/// a + b * s: a signed (doubled) area as a function of the time s since the current time.
struct Lin {
  double a = 0;
  double b = 0;
  double at(double s) const { return a + b * s; }
};

/// max over s in [0, hi] of min_i f_i(s), and the smallest such s found (a concave piecewise-linear
/// function: its maximum is at an end or where two of the lines cross).
std::pair<double, double> maximin(const std::vector<Lin>& f, double hi) {
  auto eval = [&](double s) {
    double m = std::numeric_limits<double>::infinity();
    for (const Lin& l : f) m = std::min(m, l.at(s));
    return m;
  };
  double best_s = 0;
  double best = eval(0);
  auto consider = [&](double s) {
    if (!(s > 0 && s <= hi)) return;
    const double v = eval(s);
    if (v > best) {
      best = v;
      best_s = s;
    }
  };
  consider(hi);
  for (std::size_t i = 0; i < f.size(); ++i)
    for (std::size_t j = i + 1; j < f.size(); ++j)
      if (f[i].b != f[j].b) consider((f[j].a - f[i].a) / (f[i].b - f[j].b));
  return {best, best_s};
}

/// Where a point is held: a warp triangle with barycentric weights (in the triangle's stored
/// vertex order), a warp vertex it follows exactly, or neither (a border point: fixed).
struct Binding {
  int tri = -1;
  int vertex = -1;
  std::array<double, 3> w{};
};

class Warper {
 public:
  Warper(const WarpOptions& options, const Context& context) : opt_(options), ctx_(context) {}

  void build(const std::vector<Vec2>& features);
  void bind_all(const std::vector<Vec2>& points);
  void move_all(const std::vector<Vec2>& targets);
  WarpResult finish();

 private:
  using Triple = std::array<int, 3>;

  // --- warp mesh ---
  int local(int t, int v) const {
    for (int i = 0; i < 3; ++i)
      if (tri_[t][i] == v) return i;
    return -1;
  }
  Lin lin(const Triple& v, int moving, const Vec2& d) const;
  void star(int v, std::vector<int>& out) const;
  void flip(int t, int j);
  void replace_neighbor(int t, int from, int to) {
    if (t < 0) return;
    for (int i = 0; i < 3; ++i)
      if (nb_[t][i] == from) nb_[t][i] = to;
  }

  // --- points ---
  Binding bind_in(const Vec2& p, int t) const;
  double min_weight(const Vec2& p, int t) const;
  Vec2 position(const Binding& b) const {
    if (b.vertex >= 0) return pos_[b.vertex];
    const Triple& v = tri_[b.tri];
    return b.w[0] * pos_[v[0]] + b.w[1] * pos_[v[1]] + b.w[2] * pos_[v[2]];
  }
  void attach(int i, const Binding& b) {
    bind_[i] = b;
    if (b.tri >= 0 && b.vertex < 0) tri_points_[b.tri].push_back(i);
  }
  void flip_and_rebind(int t, int j);
  /// The diagonal that flipping the edge opposite tri_[t][j] would make, as a sorted vertex pair.
  std::array<int, 2> new_diagonal(int t, int j) const;
  /// True when that flip would make again an edge removed at the current event time (removed_).
  bool recreates(int t, int j) const {
    return std::find(removed_.begin(), removed_.end(), new_diagonal(t, j)) != removed_.end();
  }

  // --- motion ---
  void move_leg(int k, const Vec2& q);
  void count_event(int k);
  bool illegal(int t, int j) const;
  void lawson(int v, int k);
  void event_flip(int k, const Vec2& p, const Vec2& d, double& time);
  double entering_time(int t, int j, int v, const Vec2& d, double time) const;
  bool flip_if_valid(int t, int j, int k);
  bool try_flip(int t, int j, int moving, const Vec2& p, const Vec2& d, double& time, double t_event,
                const std::vector<Lin>& star_lins);
  int path_blocker(int k, const Vec2& a, const Vec2& b) const;
  int spot_blocker(int k, const Vec2& w, double d) const;
  bool find_waypoint(int k, const Vec2& goal, bool both_legs, Vec2& out) const;

  WarpOptions opt_;
  const Context& ctx_;
  std::vector<Vec2> pos_;      ///< warp vertices: 4 corners, then the features (current positions)
  std::vector<Triple> tri_;    ///< CCW
  std::vector<Triple> nb_;     ///< nb_[t][i]: triangle across the edge opposite tri_[t][i]; -1 on the border
  std::vector<int> vtri_;      ///< one triangle per vertex
  std::vector<Vec2> input_;    ///< clamped input points
  std::vector<Binding> bind_;  ///< per point
  std::vector<std::vector<int>> tri_points_;  ///< points bound to each triangle (not pinned)
  std::vector<Vec2> scratch_;
  /// Edges (sorted vertex pairs) flipped away at the current event time of the moving feature. No
  /// Delaunay flip (kinetic or Lawson) makes one of them again at that time: exact flips never
  /// would (the lifted surface only goes down), but a nearly cocircular quad can look non-Delaunay
  /// across both diagonals within rounding, which would flip it back and forth forever.
  std::vector<std::array<int, 2>> removed_;
  int events_ = 0;
  int detours_ = 0;
};

void Warper::build(const std::vector<Vec2>& features) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
  using Tds = CGAL::Triangulation_data_structure_2<Vb>;
  using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;

  pos_.assign(kCornerPos.begin(), kCornerPos.end());
  pos_.insert(pos_.end(), features.begin(), features.end());
  const int n = static_cast<int>(pos_.size());

  Delaunay dt;
  Delaunay::Face_handle hint;
  for (int i = 0; i < n; ++i) {  // one at a time, in index order: deterministic
    auto vh = dt.insert(K::Point_2(pos_[i].x(), pos_[i].y()), hint);
    vh->info() = i;
    hint = vh->face();
  }
  if (static_cast<int>(dt.number_of_vertices()) != n)
    throw InternalError("warp_square: the Delaunay warp mesh lost a vertex");
  for (auto f = dt.finite_faces_begin(); f != dt.finite_faces_end(); ++f)
    tri_.push_back({f->vertex(0)->info(), f->vertex(1)->info(), f->vertex(2)->info()});
  const int nt = static_cast<int>(tri_.size());
  if (nt != 2 * n - 6) throw InternalError("warp_square: unexpected warp mesh (" + std::to_string(nt) + " triangles)");

  std::map<std::pair<int, int>, std::pair<int, int>> edges;  // directed edge -> (triangle, opposite local)
  for (int t = 0; t < nt; ++t)
    for (int j = 0; j < 3; ++j) edges[{tri_[t][(j + 1) % 3], tri_[t][(j + 2) % 3]}] = {t, j};
  nb_.assign(nt, {-1, -1, -1});
  vtri_.assign(n, -1);
  for (int t = 0; t < nt; ++t) {
    if (!(orient(pos_[tri_[t][0]], pos_[tri_[t][1]], pos_[tri_[t][2]]) > 0))
      throw InternalError("warp_square: a Delaunay warp triangle is not counter-clockwise");
    for (int j = 0; j < 3; ++j) {
      vtri_[tri_[t][j]] = t;
      auto it = edges.find({tri_[t][(j + 2) % 3], tri_[t][(j + 1) % 3]});
      if (it != edges.end()) nb_[t][j] = it->second.first;
    }
  }
  tri_points_.assign(nt, {});
}

double Warper::min_weight(const Vec2& p, int t) const {
  const Vec2& a = pos_[tri_[t][0]];
  const Vec2& b = pos_[tri_[t][1]];
  const Vec2& c = pos_[tri_[t][2]];
  const double area = orient(a, b, c);
  return std::min({cross2(b - p, c - p), cross2(p - a, c - a), cross2(b - a, p - a)}) / area;
}

Binding Warper::bind_in(const Vec2& p, int t) const {
  const Triple& v = tri_[t];
  const Vec2& a = pos_[v[0]];
  const Vec2& b = pos_[v[1]];
  const Vec2& c = pos_[v[2]];
  // Written so that p equal to a vertex gives exactly (1, 0, 0) in that vertex's slot.
  const double area = orient(a, b, c);
  Binding out;
  out.tri = t;
  out.w = {cross2(b - p, c - p) / area, cross2(p - a, c - a) / area, cross2(b - a, p - a) / area};
  int nonzero = 0;
  double sum = 0;
  for (int i = 0; i < 3; ++i) {
    if (!(out.w[i] >= kTinyWeight)) out.w[i] = 0;
    if (out.w[i] > 0) ++nonzero;
    sum += out.w[i];
  }
  if (nonzero == 0) throw InternalError("warp_square: a point fell outside its warp triangles");
  for (double& w : out.w) w /= sum;
  if (nonzero == 1)
    for (int i = 0; i < 3; ++i)
      if (out.w[i] > 0) out.vertex = v[i];
  return out;
}

void Warper::bind_all(const std::vector<Vec2>& points) {
  const int np = static_cast<int>(points.size());
  const int nt = static_cast<int>(tri_.size());
  // A uniform grid over the square; each cell lists the triangles whose bounding box meets it.
  const int g = std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(nt)))), 1, 256);
  auto cell = [g](double x) { return std::clamp(static_cast<int>(x * g), 0, g - 1); };
  std::vector<int> start(g * g + 1, 0);
  std::vector<std::array<int, 4>> boxes(nt);
  for (int t = 0; t < nt; ++t) {
    Vec2 lo = pos_[tri_[t][0]], hi = lo;
    for (int i = 1; i < 3; ++i) {
      lo = lo.cwiseMin(pos_[tri_[t][i]]);
      hi = hi.cwiseMax(pos_[tri_[t][i]]);
    }
    boxes[t] = {cell(lo.x() - 1e-9), cell(hi.x() + 1e-9), cell(lo.y() - 1e-9), cell(hi.y() + 1e-9)};
    for (int y = boxes[t][2]; y <= boxes[t][3]; ++y)
      for (int x = boxes[t][0]; x <= boxes[t][1]; ++x) ++start[y * g + x + 1];
  }
  for (int c = 0; c < g * g; ++c) start[c + 1] += start[c];
  std::vector<int> items(start.back());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (int t = 0; t < nt; ++t)
    for (int y = boxes[t][2]; y <= boxes[t][3]; ++y)
      for (int x = boxes[t][0]; x <= boxes[t][1]; ++x) items[fill[y * g + x]++] = t;

  input_.resize(np);
  bind_.assign(np, Binding{});
  for (int i = 0; i < np; ++i) {
    const Vec2 p(std::clamp(points[i].x(), 0.0, 1.0), std::clamp(points[i].y(), 0.0, 1.0));
    input_[i] = p;
    if (p.x() == 0 || p.x() == 1 || p.y() == 0 || p.y() == 1) continue;  // border: fixed
    const int c = cell(p.y()) * g + cell(p.x());
    int best_t = -1;
    double best = -std::numeric_limits<double>::infinity();
    for (int k = start[c]; k < start[c + 1]; ++k) {
      const double w = min_weight(p, items[k]);
      if (w > best) {
        best = w;
        best_t = items[k];
        if (w >= 0) break;
      }
    }
    if (best_t < 0 || best < -1e-9)
      throw InternalError("warp_square: point location failed for point " + std::to_string(i) + " at " + str(p));
    attach(i, bind_in(p, best_t));
  }
}

Lin Warper::lin(const Triple& v, int moving, const Vec2& d) const {
  Lin out;
  out.a = orient(pos_[v[0]], pos_[v[1]], pos_[v[2]]);
  for (int i = 0; i < 3; ++i) {
    if (v[i] != moving) continue;
    // cross2(q - p, r - p) with p = p0 + s d is linear in s with slope cross2(d, q - r).
    out.b = cross2(d, pos_[v[(i + 1) % 3]] - pos_[v[(i + 2) % 3]]);
  }
  return out;
}

void Warper::star(int v, std::vector<int>& out) const {
  out.clear();
  const int t0 = vtri_[v];
  int t = t0;
  do {
    out.push_back(t);
    const int i = local(t, v);
    t = nb_[t][(i + 2) % 3];  // across the edge (v, next vertex)
  } while (t != t0 && t >= 0 && out.size() <= tri_.size());
  if (t != t0) throw InternalError("warp_square: the star of a feature is not closed");
}

void Warper::flip(int t, int j) {
  const int u = nb_[t][j];
  const int a = tri_[t][j], b = tri_[t][(j + 1) % 3], c = tri_[t][(j + 2) % 3];
  int k = 0;
  while (tri_[u][k] == b || tri_[u][k] == c) ++k;
  const int d = tri_[u][k];  // u = (d, c, b)
  const int n_ab = nb_[t][(j + 2) % 3];
  const int n_ca = nb_[t][(j + 1) % 3];
  const int n_bd = nb_[u][(k + 1) % 3];
  const int n_dc = nb_[u][(k + 2) % 3];
  tri_[t] = {a, b, d};
  nb_[t] = {n_bd, u, n_ab};
  tri_[u] = {a, d, c};
  nb_[u] = {n_dc, n_ca, t};
  replace_neighbor(n_bd, u, t);
  replace_neighbor(n_ca, t, u);
  vtri_[a] = vtri_[b] = vtri_[d] = t;
  vtri_[c] = u;
}

void Warper::flip_and_rebind(int t, int j) {
  const int u = nb_[t][j];
  std::vector<int> ids;
  ids.swap(tri_points_[t]);
  ids.insert(ids.end(), tri_points_[u].begin(), tri_points_[u].end());
  tri_points_[u].clear();
  scratch_.resize(ids.size());
  for (std::size_t i = 0; i < ids.size(); ++i) scratch_[i] = position(bind_[ids[i]]);
  flip(t, j);
  for (const int tt : {t, u})
    if (!(orient(pos_[tri_[tt][0]], pos_[tri_[tt][1]], pos_[tri_[tt][2]]) > 0))
      throw SolverError("warp_square: a flip produced a non-positive warp triangle (numerical breakdown)");
  for (std::size_t i = 0; i < ids.size(); ++i) {
    const Vec2& p = scratch_[i];
    attach(ids[i], bind_in(p, min_weight(p, t) >= min_weight(p, u) ? t : u));
  }
}

std::array<int, 2> Warper::new_diagonal(int t, int j) const {
  const int u = nb_[t][j];
  if (u < 0) return {-1, -1};
  const int a = tri_[t][j], b = tri_[t][(j + 1) % 3], c = tri_[t][(j + 2) % 3];
  int m = 0;
  while (tri_[u][m] == b || tri_[u][m] == c) ++m;
  return {std::min(a, tri_[u][m]), std::max(a, tri_[u][m])};
}

bool Warper::try_flip(int t, int j, int moving, const Vec2& p, const Vec2& d, double& time, double t_event,
                      const std::vector<Lin>& star_lins) {
  const int u = nb_[t][j];
  if (u < 0) return false;  // a side of the square: never flipped
  const int a = tri_[t][j], b = tri_[t][(j + 1) % 3], c = tri_[t][(j + 2) % 3];
  int k = 0;
  while (tri_[u][k] == b || tri_[u][k] == c) ++k;
  const int dv = tri_[u][k];
  const Lin l1 = lin({a, b, dv}, moving, d);
  const Lin l2 = lin({a, dv, c}, moving, d);
  const double s_event = t_event - time;
  // The new triangles must outlive the event (else the flip makes no progress) ...
  if (!(l1.at(s_event) > kMinArea2 && l2.at(s_event) > kMinArea2)) return false;
  // ... and there must be a time before it where every triangle involved is positive.
  std::vector<Lin> f = star_lins;
  f.push_back(lin(tri_[u], moving, d));
  f.push_back(l1);
  f.push_back(l2);
  const auto [best, s] = maximin(f, std::min(t_event, 1.0) - time);
  if (!(best > kMinArea2)) return false;
  if (s > 0) {
    time += s;
    pos_[moving] = p + time * d;
  }
  removed_.push_back({std::min(b, c), std::max(b, c)});
  flip_and_rebind(t, j);
  return true;
}

void Warper::count_event(int k) {
  if (++events_ > opt_.max_events)
    throw SolverError("warp_square: meshes too different to align: more than " + std::to_string(opt_.max_events) +
                      " flip events (options.max_events) while moving feature " + std::to_string(k) +
                      "; move the features closer to their targets or raise the limit");
  if (events_ % 64 == 0) ctx_.check_cancel();
}

bool Warper::illegal(int t, int j) const {
  const int u = nb_[t][j];
  if (u < 0) return false;
  const Triple& v = tri_[t];
  const int b = v[(j + 1) % 3], c = v[(j + 2) % 3];
  int k = 0;
  while (tri_[u][k] == b || tri_[u][k] == c) ++k;
  const Vec2 d = pos_[tri_[u][k]];
  const Vec2 ad = pos_[v[j]] - d, bd = pos_[b] - d, cd = pos_[c] - d;
  const double t1 = ad.squaredNorm() * cross2(bd, cd);
  const double t2 = bd.squaredNorm() * cross2(cd, ad);
  const double t3 = cd.squaredNorm() * cross2(ad, bd);
  // d strictly inside the circumcircle of (a, b, c), beyond rounding (nearly cocircular: keep).
  if (!(t1 + t2 + t3 > kIncircleTolerance * (std::abs(t1) + std::abs(t2) + std::abs(t3)))) return false;
  // An illegal edge has a strictly convex quadrilateral; make sure the new triangles are positive.
  const Vec2& a = pos_[v[j]];
  return orient(a, pos_[b], d) > kMinArea2 && orient(a, d, pos_[c]) > kMinArea2;
}

/// Restores the Delaunay property around v at the current positions (Lawson flips of the edges
/// that are non-Delaunay beyond rounding); the points keep their positions. Flips that would make
/// again an edge of removed_ are not done, and every edge flipped away is added to it (the caller
/// clears it when the event time changes): at most one flip per vertex pair, so this terminates.
void Warper::lawson(int v, int k) {
  // Only edges whose quadrilateral contains v can have changed; flips propagate to their quads.
  // An edge is kept as (triangle, its two vertices); when that triangle no longer holds both, the
  // edge was flipped away (an edge made again later is pushed by the flip that makes it).
  std::vector<std::array<int, 3>> stack;
  std::vector<int> around;
  star(v, around);
  for (const int t : around)
    for (int j = 0; j < 3; ++j) stack.push_back({t, tri_[t][(j + 1) % 3], tri_[t][(j + 2) % 3]});
  while (!stack.empty()) {
    const auto [t, a, b] = stack.back();
    stack.pop_back();
    const int ia = local(t, a), ib = local(t, b);
    if (ia < 0 || ib < 0) continue;
    const int j = 3 - ia - ib;  // the local vertex opposite the edge
    if (!illegal(t, j) || recreates(t, j)) continue;
    const int u = nb_[t][j];
    removed_.push_back({std::min(a, b), std::max(a, b)});
    flip_and_rebind(t, j);
    count_event(k);
    for (const int tt : {t, u})
      for (int m = 0; m < 3; ++m) stack.push_back({tt, tri_[tt][(m + 1) % 3], tri_[tt][(m + 2) % 3]});
  }
}

/// Flips, just before the earliest degeneration of a triangle around the moving feature, the edge
/// opposite the middle vertex of the collinear triple (or another edge of that triangle if that
/// flip is not valid), moving the feature to the flip time; SolverError if no flip is valid.
void Warper::event_flip(int k, const Vec2& p, const Vec2& d, double& time) {
  const int v = kCorners + k;
  std::vector<int> around;
  std::vector<Lin> lins;
  std::vector<std::pair<double, int>> dying;
  star(v, around);
  for (std::size_t i = 0; i < around.size(); ++i) {
    lins.push_back(lin(tri_[around[i]], v, d));
    if (lins.back().b < 0) {
      const double t_zero = time + std::max(lins.back().a, 0.0) / -lins.back().b;
      if (t_zero <= 1 + kEndTolerance) dying.emplace_back(t_zero, static_cast<int>(i));
    }
  }
  std::sort(dying.begin(), dying.end());
  for (const auto& [t_event, i] : dying) {
    const int t = around[i];
    // The middle vertex of the collinear triple at the event: the one not on the longest side.
    std::array<Vec2, 3> at;
    for (int m = 0; m < 3; ++m) at[m] = tri_[t][m] == v ? Vec2(p + t_event * d) : pos_[tri_[t][m]];
    int middle = 0;
    double longest = -1;
    for (int m = 0; m < 3; ++m) {
      const double len = (at[(m + 1) % 3] - at[(m + 2) % 3]).squaredNorm();
      if (len > longest) {
        longest = len;
        middle = m;
      }
    }
    for (const int j : {middle, (middle + 1) % 3, (middle + 2) % 3}) {
      if (try_flip(t, j, v, p, d, time, t_event, lins)) {
        count_event(k);
        return;
      }
    }
  }
  std::ostringstream s;
  s << "warp_square: cannot resolve a degenerate configuration while moving feature " << k << " from " << str(p)
    << " to " << str(p + d) << " (at time " << (dying.empty() ? time : dying.front().first) << ")";
  throw SolverError(s.str());
}

/// The first time in [time, 1 + kEndTolerance] at which the edge opposite tri_[t][j] turns
/// non-Delaunay while v moves with velocity d (the incircle value crosses 0 upwards), or infinity.
double Warper::entering_time(int t, int j, int v, const Vec2& d, double time) const {
  const int u = nb_[t][j];
  if (u < 0) return std::numeric_limits<double>::infinity();
  const Triple& w = tri_[t];
  const int b = w[(j + 1) % 3], c = w[(j + 2) % 3];
  int m = 0;
  while (tri_[u][m] == b || tri_[u][m] == c) ++m;
  const std::array<int, 4> ids = {w[j], b, c, tri_[u][m]};
  // f(s) = incircle of the quad with v moved by s * d: a quadratic in s, fitted on [0, span].
  auto f = [&](double s) {
    std::array<Vec2, 4> x;
    for (int i = 0; i < 4; ++i) x[i] = ids[i] == v ? Vec2(pos_[v] + s * d) : pos_[ids[i]];
    return incircle(x[0], x[1], x[2], x[3]);
  };
  const double span = 1 + kEndTolerance - time;
  if (!(span > 0)) return std::numeric_limits<double>::infinity();
  const double f0 = f(0), fh = f(0.5 * span), f1 = f(span);
  const double c0 = f0;
  const double c1 = (4 * fh - 3 * f0 - f1) / span;
  const double c2 = 2 * (f1 - 2 * fh + f0) / (span * span);
  if (f0 > 0 && c1 > 0) return time;  // illegal within rounding already, and getting worse
  std::array<double, 2> roots = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  const double disc = c1 * c1 - 4 * c2 * c0;
  if (c2 == 0) {
    if (c1 != 0) roots[0] = -c0 / c1;
  } else if (disc >= 0) {
    const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
    roots[0] = q / c2;
    if (q != 0) roots[1] = c0 / q;
  }
  std::sort(roots.begin(), roots.end());
  for (const double r : roots)
    if (r >= 0 && r <= span && 2 * c2 * r + c1 > 0) return time + r;
  return std::numeric_limits<double>::infinity();
}

void Warper::move_leg(int k, const Vec2& q) {
  const int v = kCorners + k;
  const Vec2 p = pos_[v];
  const Vec2 d = q - p;
  if (d.x() == 0 && d.y() == 0) return;
  removed_.clear();
  lawson(v, k);
  double time = 0;
  std::vector<int> around;
  // Edges not to flip again at the current event time: those just made by a flip there (a mover
  // moving tangentially to a circle would otherwise flip the two diagonals back and forth), and
  // those whose flip failed there (rounding). Flips that would make again an edge removed at that
  // time (removed_, shared with lawson) are not done either.
  std::vector<std::array<int, 2>> skipped;
  double skip_time = 0;  // the time of the first Lawson pass above
  auto edge = [](int a, int b) { return std::array<int, 2>{std::min(a, b), std::max(a, b)}; };
  while (true) {
    // Kinetic Delaunay: the next time an edge around v stops being Delaunay, and (a guard that
    // only rounding can trigger) the next time a triangle around v degenerates.
    star(v, around);
    double t_zero = std::numeric_limits<double>::infinity();
    double t_flip = std::numeric_limits<double>::infinity();
    int flip_t = -1, flip_j = -1;
    for (const int t : around) {
      const Lin l = lin(tri_[t], v, d);
      if (l.b < 0) t_zero = std::min(t_zero, time + std::max(l.a, 0.0) / -l.b);
      for (int j = 0; j < 3; ++j) {
        const double te = entering_time(t, j, v, d, time);
        if (!(te < t_flip)) continue;
        if (std::min(te, 1.0) <= skip_time + kSameTime &&
            (std::find(skipped.begin(), skipped.end(), edge(tri_[t][(j + 1) % 3], tri_[t][(j + 2) % 3])) !=
                 skipped.end() ||
             recreates(t, j)))
          continue;
        t_flip = te;
        flip_t = t;
        flip_j = j;
      }
    }
    if (t_flip > 1 + kEndTolerance && t_zero > 1 + kEndTolerance) break;
    if (t_zero <= t_flip) {
      // Only rounding lets a triangle degenerate before its edge turns non-Delaunay: flip at the
      // exact degeneration event instead.
      skipped.clear();
      removed_.clear();
      event_flip(k, p, d, time);  // records the edge it flips away in removed_
      skip_time = time;
      continue;
    }
    // At the cocircular moment the quad is convex, so the flip is valid (checked against rounding).
    time = std::max(time, std::min(t_flip, 1.0));
    pos_[v] = p + time * d;
    if (time > skip_time + kSameTime) {
      skipped.clear();
      removed_.clear();
      skip_time = time;
    }
    const std::array<int, 2> old_edge =
        edge(tri_[flip_t][(flip_j + 1) % 3], tri_[flip_t][(flip_j + 2) % 3]);
    if (flip_if_valid(flip_t, flip_j, k)) {
      removed_.push_back(old_edge);
      skipped.push_back(edge(tri_[flip_t][0], tri_[flip_t][2]));  // the new diagonal
      lawson(v, k);
    } else {
      skipped.push_back(old_edge);
    }
  }
  pos_[v] = q;
  if (1.0 > skip_time + kSameTime) removed_.clear();
  lawson(v, k);
  star(v, around);
  for (const int t : around)
    if (!(orient(pos_[tri_[t][0]], pos_[tri_[t][1]], pos_[tri_[t][2]]) > 0))
      throw SolverError("warp_square: feature " + std::to_string(k) + " ended on a non-positive warp triangle at " +
                        str(q) + " (numerical breakdown)");
}

bool Warper::flip_if_valid(int t, int j, int k) {
  const int u = nb_[t][j];
  if (u < 0) return false;
  const int a = tri_[t][j], b = tri_[t][(j + 1) % 3], c = tri_[t][(j + 2) % 3];
  int m = 0;
  while (tri_[u][m] == b || tri_[u][m] == c) ++m;
  const int dv = tri_[u][m];
  if (!(orient(pos_[a], pos_[b], pos_[dv]) > kMinArea2 && orient(pos_[a], pos_[dv], pos_[c]) > kMinArea2)) return false;
  if (!(orient(pos_[a], pos_[b], pos_[c]) > kMinArea2 && orient(pos_[dv], pos_[c], pos_[b]) > kMinArea2)) return false;
  flip_and_rebind(t, j);
  count_event(k);
  return true;
}

/// The first other feature within min_feature_distance / 2 of the segment a-b, or -1.
int Warper::path_blocker(int k, const Vec2& a, const Vec2& b) const {
  const double clearance = 0.5 * opt_.min_feature_distance;
  const Vec2 lo = a.cwiseMin(b).array() - clearance, hi = a.cwiseMax(b).array() + clearance;
  for (int j = kCorners; j < static_cast<int>(pos_.size()); ++j) {
    const Vec2& x = pos_[j];
    if (x.x() < lo.x() || x.x() > hi.x() || x.y() < lo.y() || x.y() > hi.y() || j - kCorners == k) continue;
    if (segment_distance(x, a, b) < clearance) return j - kCorners;
  }
  return -1;
}

/// The first other feature closer than d to w, or -1.
int Warper::spot_blocker(int k, const Vec2& w, double d) const {
  for (int j = kCorners; j < static_cast<int>(pos_.size()); ++j)
    if (j - kCorners != k && (pos_[j] - w).norm() < d) return j - kCorners;
  return -1;
}

/// A stop for feature k on the way to `goal`: at least min_feature_distance from the border and
/// every other feature, reachable on a clear straight leg and, with both_legs, leaving a clear leg
/// to the goal. Tries points beside the straight path first, then a grid over the square.
bool Warper::find_waypoint(int k, const Vec2& goal, bool both_legs, Vec2& out) const {
  const double m = opt_.min_feature_distance;
  const Vec2 p = pos_[kCorners + k];
  const Vec2 dir = goal - p;
  const double len = dir.norm();
  const Vec2 along = len > 0 ? Vec2(dir / len) : Vec2(1, 0);
  const Vec2 side(-along.y(), along.x());
  const double scale = std::max(len, 8 * m);
  std::vector<Vec2> candidates;
  for (const double f : {0.5, 0.25, 0.75})
    for (const double s : {0.25, 0.5, 1.0, 0.125, 2.0, 0.0625, 4.0})
      for (const double sign : {1.0, -1.0}) candidates.push_back(p + f * dir + sign * s * scale * side);
  std::vector<Vec2> grid;
  for (int y = 0; y < 32; ++y)
    for (int x = 0; x < 32; ++x) grid.emplace_back((x + 0.5) / 32, (y + 0.5) / 32);
  const Vec2 mid = p + 0.5 * dir;
  std::stable_sort(grid.begin(), grid.end(),
                   [&](const Vec2& a, const Vec2& b) { return (a - mid).squaredNorm() < (b - mid).squaredNorm(); });
  candidates.insert(candidates.end(), grid.begin(), grid.end());
  for (const Vec2& w : candidates) {
    if (border_distance(w) < m || spot_blocker(k, w, m) >= 0 || path_blocker(k, p, w) >= 0) continue;
    if (both_legs && path_blocker(k, w, goal) >= 0) continue;
    out = w;
    return true;
  }
  return false;
}

void Warper::move_all(const std::vector<Vec2>& targets) {
  const int e = static_cast<int>(targets.size());
  const double clearance = 0.5 * opt_.min_feature_distance;
  std::vector<char> done(e);
  for (int k = 0; k < e; ++k) done[k] = pos_[kCorners + k] == targets[k];
  int finished = static_cast<int>(std::count(done.begin(), done.end(), 1));
  const int max_detours = 4 * e + 16;
  // Rounds 1 .. rounds-1: every waiting feature in index order advances to its share of the
  // straight path, if that step is clear; whatever is left is done by the planner below.
  const std::vector<Vec2> start(pos_.begin() + kCorners, pos_.end());
  for (int r = 1; r < opt_.rounds && finished < e; ++r) {
    ctx_.check_cancel();
    ctx_.report("warp", static_cast<double>(r - 1) / opt_.rounds);
    const double f = static_cast<double>(r) / opt_.rounds;
    for (int k = 0; k < e; ++k) {
      if (done[k]) continue;
      const Vec2 w = start[k] + f * (targets[k] - start[k]);
      if (border_distance(w) < opt_.min_feature_distance || spot_blocker(k, w, opt_.min_feature_distance) >= 0 ||
          path_blocker(k, pos_[kCorners + k], w) >= 0)
        continue;
      move_leg(k, w);
    }
  }
  while (finished < e) {
    ctx_.check_cancel();
    ctx_.report("warp", (opt_.rounds - 1 + static_cast<double>(finished) / e) / opt_.rounds);
    // The lowest-index feature with a clear straight path goes next.
    int next = -1;
    for (int k = 0; k < e && next < 0; ++k)
      if (!done[k] && path_blocker(k, pos_[kCorners + k], targets[k]) < 0) next = k;
    if (next >= 0) {
      move_leg(next, targets[next]);
      done[next] = 1;
      ++finished;
      continue;
    }
    // Every remaining path is blocked. Follow "target occupied by" links from the first waiting
    // feature: either to a feature whose target is free (it detours around the blocker) or
    // around a cycle (a feature of the cycle steps aside, freeing its place).
    int cur = 0;
    while (done[cur]) ++cur;
    std::vector<char> seen(e, 0);
    seen[cur] = 1;
    bool cycle = false;
    while (true) {
      const int j = spot_blocker(cur, targets[cur], clearance);
      if (j < 0) break;
      cur = j;
      if (seen[j]) {
        cycle = true;
        break;
      }
      seen[j] = 1;
    }
    if (++detours_ > max_detours)
      throw SolverError("warp_square: no collision-free order found for the features after " +
                        std::to_string(max_detours) + " detours");
    Vec2 w;
    if (!find_waypoint(cur, targets[cur], !cycle, w) && !(!cycle && find_waypoint(cur, targets[cur], false, w)))
      throw SolverError("warp_square: no collision-free path for feature " + std::to_string(cur) + " from " +
                        str(pos_[kCorners + cur]) + " to " + str(targets[cur]) +
                        " (too crowded for min_feature_distance)");
    move_leg(cur, w);
  }
  ctx_.report("warp", 1.0);
}

WarpResult Warper::finish() {
  WarpResult r;
  r.events = events_;
  r.detours = detours_;
  r.warp_triangles = static_cast<int>(tri_.size());
  r.triangles = tri_;
  r.min_warp_area = std::numeric_limits<double>::infinity();
  for (const Triple& t : tri_)
    r.min_warp_area = std::min(r.min_warp_area, 0.5 * orient(pos_[t[0]], pos_[t[1]], pos_[t[2]]));
  if (!(r.min_warp_area > 0))
    throw SolverError("warp_square: the warp mesh is not positive at the end (smallest triangle area " +
                      std::to_string(r.min_warp_area) + ")");
  r.points.resize(input_.size());
  for (std::size_t i = 0; i < input_.size(); ++i) {
    const Binding& b = bind_[i];
    if (b.tri < 0 && b.vertex < 0) {
      r.points[i] = input_[i];
      continue;
    }
    const Vec2 q = position(b);
    if (!(q.x() >= -kOutsideTolerance && q.x() <= 1 + kOutsideTolerance && q.y() >= -kOutsideTolerance &&
          q.y() <= 1 + kOutsideTolerance))
      throw SolverError("warp_square: point " + std::to_string(i) + " left the square (" + str(q) + ")");
    r.points[i] = Vec2(std::clamp(q.x(), 0.0, 1.0), std::clamp(q.y(), 0.0, 1.0));
  }
  return r;
}

}  // namespace

WarpResult warp_square(const std::vector<Vec2>& features, const std::vector<Vec2>& targets,
                       const std::vector<Vec2>& points, const WarpOptions& options, const Context& context) {
  validate(features, targets, points, options);
  context.check_cancel();
  Warper w(options, context);
  w.build(features);
  w.bind_all(points);
  w.move_all(targets);
  return w.finish();
}

}  // namespace qs::warp
