#include "qs/merge/merge.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/core/parallel.h"

namespace qs::merge {
namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;
using EPoint = Epeck::Point_2;

// Exact orientation of three double points: +1 counter-clockwise, -1 clockwise, 0 collinear.
int orient(const Vec2& p, const Vec2& q, const Vec2& r) {
  return static_cast<int>(CGAL::orientation(Epick::Point_2(p.x(), p.y()), Epick::Point_2(q.x(), q.y()),
                                            Epick::Point_2(r.x(), r.y())));
}

// A merged face with less than this fraction of its parent's area is too thin for its double
// positions to have a normal (two crossings a rounding apart): counted, not judged.
constexpr double kThinFace = 1e-12;

std::string uv_string(const Vec2& p) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << p.x() << ", " << p.y() << ")";
  return s.str();
}

// One patch of one chart with local vertex ids.
struct PatchMesh {
  std::vector<int> faces;                 // chart face ids, in chart order
  std::vector<std::array<int, 3>> local;  // per face, local vertex ids
  std::vector<int> vertex;                // local -> chart vertex id
  std::vector<Vec2> uv;                   // local
};

std::vector<std::vector<int>> faces_by_patch(const dissect::Chart& chart, int patches) {
  std::vector<std::vector<int>> by(patches);
  for (int f = 0; f < chart.mesh.num_faces(); ++f) {
    const int p = chart.face_patch[f];
    if (p < 0 || p >= patches) throw InvalidInput("chart face " + std::to_string(f) + " has patch " + std::to_string(p));
    by[p].push_back(f);
  }
  return by;
}

std::string patch_label(const dissect::Chart& chart, int p) {
  const std::string& n = p < static_cast<int>(chart.patches.size()) ? chart.patches[p].name : std::string();
  return "patch " + std::to_string(p) + (n.empty() ? "" : " ('" + n + "')");
}

// Builds the patch's local mesh and checks it exactly (see check_chart_uv).
PatchMesh build_patch(const dissect::Chart& chart, const std::vector<int>& faces, int p, const std::string& name) {
  PatchMesh pm;
  pm.faces = faces;
  pm.local.resize(faces.size());
  std::unordered_map<int, int> index;
  index.reserve(faces.size());
  const std::string where = name + ": " + patch_label(chart, p);
  for (size_t i = 0; i < faces.size(); ++i) {
    const int f = faces[i];
    for (int k = 0; k < 3; ++k) {
      const int v = chart.mesh.faces[f][k];
      const Vec2& uv = chart.face_uv[f][k];
      if (!(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1))
        throw InvalidInput(where + ": face " + std::to_string(f) + " has uv " + uv_string(uv) +
                           " outside the unit square (expected every uv in [0, 1]^2)");
      auto [it, fresh] = index.emplace(v, static_cast<int>(pm.vertex.size()));
      if (fresh) {
        pm.vertex.push_back(v);
        pm.uv.push_back(uv);
      } else if (pm.uv[it->second] != uv) {
        throw InvalidInput(where + ": vertex " + std::to_string(v) + " has two uv in the patch, " +
                           uv_string(pm.uv[it->second]) + " and " + uv_string(uv) + " (face " + std::to_string(f) +
                           "); expected one (u, v) per vertex and patch");
      }
      pm.local[i][k] = it->second;
    }
    const auto& t = pm.local[i];
    const int o = orient(pm.uv[t[0]], pm.uv[t[1]], pm.uv[t[2]]);
    if (o <= 0)
      throw InvalidInput(where + ": face " + std::to_string(f) + " has a " + (o < 0 ? "flipped" : "degenerate") +
                         " uv triangle " + uv_string(pm.uv[t[0]]) + " " + uv_string(pm.uv[t[1]]) + " " +
                         uv_string(pm.uv[t[2]]) + " (exact test); qs-merge needs every patch's map bijective: "
                         "dissect again (a version-1 chart stores uv as float32; qs-dissect now writes float64)");
  }
  // Border edges (one face in the patch) must lie on one side of the square; the areas sum to 1.
  std::unordered_map<long long, int> edge_count;
  edge_count.reserve(3 * faces.size());
  const long long n = static_cast<long long>(pm.vertex.size());
  double area = 0;
  for (const auto& t : pm.local) {
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      ++edge_count[std::min(a, b) * n + std::max(a, b)];
    }
    area += 0.5 * cross2(pm.uv[t[1]] - pm.uv[t[0]], pm.uv[t[2]] - pm.uv[t[0]]);
  }
  for (const auto& t : pm.local)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const int c = edge_count[std::min(a, b) * n + std::max(a, b)];
      if (c > 2)
        throw InvalidInput(where + ": the edge between chart vertices " + std::to_string(pm.vertex[a]) + " and " +
                           std::to_string(pm.vertex[b]) + " has " + std::to_string(c) + " faces (expected at most 2)");
      if (c == 1) {
        const Vec2 &p = pm.uv[a], &q = pm.uv[b];
        const bool on_side = (p.x() == 0 && q.x() == 0) || (p.x() == 1 && q.x() == 1) || (p.y() == 0 && q.y() == 0) ||
                             (p.y() == 1 && q.y() == 1);
        if (!on_side)
          throw InvalidInput(where + ": its border edge between chart vertices " + std::to_string(pm.vertex[a]) +
                             " and " + std::to_string(pm.vertex[b]) + " is not on a side of the unit square (uv " +
                             uv_string(p) + " " + uv_string(q) + ")");
      }
    }
  if (std::abs(area - 1) > 1e-9)
    throw InvalidInput(where + ": its uv triangles cover an area of " + std::to_string(area) +
                       " (expected 1: the patch's map onto the unit square is not one-to-one)");
  return pm;
}

// A merged vertex's identity: kind 0 an A vertex (b: the B vertex it coincides with, or -1),
// kind 1 a B vertex, kind 2 a crossing of A edge (x, y) and B edge (z, w); chart vertex ids.
struct Key {
  int kind, x, y, z, w;
  bool operator==(const Key& o) const { return kind == o.kind && x == o.x && y == o.y && z == o.z && w == o.w; }
};
struct KeyHash {
  size_t operator()(const Key& k) const {
    unsigned long long h = static_cast<unsigned>(k.kind);
    for (int v : {k.x, k.y, k.z, k.w}) h = (h ^ static_cast<unsigned>(v)) * 0x100000001b3ULL + 0x9e3779b97f4a7c15ULL;
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

enum class Origin { AInFace, AOnBEdge, Coincident, BInFace, BOnAEdge, Crossing };

struct LocalVertex {
  Key key;
  Origin origin = Origin::AInFace;
  EPoint p;
  Vec2 uv;
  Vec3 pa, pb;
};

struct PatchResult {
  std::vector<LocalVertex> vertices;
  std::vector<Tri> faces;
  std::vector<int> parent_a, parent_b;
  std::vector<double> min_angle_uv;  // per face, degrees
  int polygons = 0;
};

// The smallest corner angle (degrees): the one opposite the shortest side.
double min_angle_degrees(const Vec2& p, const Vec2& q, const Vec2& r) {
  const double a = (q - r).squaredNorm(), b = (r - p).squaredNorm(), c = (p - q).squaredNorm();
  const Vec2 &o = a <= b && a <= c ? p : b <= c ? q : r;
  const Vec2 &x = a <= b && a <= c ? q : b <= c ? r : p;
  const Vec2 &y = a <= b && a <= c ? r : b <= c ? p : q;
  const Vec2 u = x - o, v = y - o;
  return std::atan2(std::abs(cross2(u, v)), u.dot(v)) * (180.0 / M_PI);
}

double min_angle_degrees(const Vec3& p, const Vec3& q, const Vec3& r) {
  const double a = (q - r).squaredNorm(), b = (r - p).squaredNorm(), c = (p - q).squaredNorm();
  const Vec3 &o = a <= b && a <= c ? p : b <= c ? q : r;
  const Vec3 &x = a <= b && a <= c ? q : b <= c ? r : p;
  const Vec3 &y = a <= b && a <= c ? r : b <= c ? p : q;
  const Vec3 u = x - o, v = y - o;
  return std::atan2(u.cross(v).norm(), u.dot(v)) * (180.0 / M_PI);
}

Vec3 lerp(const Vec3& a, const Vec3& b, double t) { return (1 - t) * a + t * b; }

// An exact number rounded to double, within 8 units in the last place: the midpoint of its
// interval when that is that tight (nearly always), else computed exactly first.
double rounded(const Epeck::FT& x) {
  CGAL::Interval_nt<false> i = x.approx();
  const double mid = 0.5 * i.inf() + 0.5 * i.sup();
  if (!(i.sup() - i.inf() <= 16 * std::numeric_limits<double>::epsilon() * std::abs(mid))) {
    x.exact();
    i = x.approx();
    return 0.5 * i.inf() + 0.5 * i.sup();
  }
  return mid;
}

Epeck::FT cross_exact(const EPoint& o, const EPoint& a, const EPoint& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

EPoint exact_point(const Vec2& p) { return EPoint(p.x(), p.y()); }

// Below this sine of the angle between two edges (or of a triangle's smallest angle, roughly),
// interpolation parameters are computed exactly and rounded once; above it in double, whose
// relative error is then below 1e-13.
constexpr double kWellConditioned = 1e-3;

// The point uv on the segment (q0, q1): the position interpolated along the segment (a
// projection: well conditioned).
Vec3 on_edge(const Vec2& uv, const Vec2& q0, const Vec2& q1, const Vec3& p0, const Vec3& p1) {
  const Vec2 d = q1 - q0;
  return lerp(p0, p1, std::clamp((uv - q0).dot(d) / d.squaredNorm(), 0.0, 1.0));
}

// The point uv inside the triangle (q0, q1, q2): barycentric interpolation; for a thin triangle
// the coordinates are computed exactly and rounded once, so that a sliver of the chart does not
// amplify rounding errors.
Vec3 in_face(const Vec2& uv, const std::array<Vec2, 3>& q, const std::array<Vec3, 3>& p) {
  const double area = cross2(q[1] - q[0], q[2] - q[0]);
  const double longest = std::max({(q[1] - q[0]).squaredNorm(), (q[2] - q[1]).squaredNorm(), (q[0] - q[2]).squaredNorm()});
  double l0, l1, l2;
  if (area > kWellConditioned * longest) {
    const Vec3 l = barycentric(q[0], q[1], q[2], uv, area);
    l0 = l[0], l1 = l[1], l2 = l[2];
  } else {
    const EPoint P = exact_point(uv), Q0 = exact_point(q[0]), Q1 = exact_point(q[1]), Q2 = exact_point(q[2]);
    const Epeck::FT twice = cross_exact(Q0, Q1, Q2);
    l0 = rounded(cross_exact(P, Q1, Q2) / twice), l1 = rounded(cross_exact(P, Q2, Q0) / twice);
    l2 = rounded(cross_exact(P, Q0, Q1) / twice);
  }
  return l0 * p[0] + l1 * p[1] + l2 * p[2];
}

class PatchMerger {
 public:
  PatchMerger(const dissect::Chart& ca, const dissect::Chart& cb, const PatchMesh& a, const PatchMesh& b,
              const MergeOptions& options)
      : ca_(ca), cb_(cb), a_(a), b_(b), options_(options) {}

  PatchResult run() {
    // Candidate A faces per B face: a uniform grid over the A faces' boxes.
    const int na = static_cast<int>(a_.local.size());
    const size_t guess = 2 * (a_.local.size() + b_.local.size());  // merged vertices: about 2x the faces
    index_.reserve(guess);
    result_.vertices.reserve(guess);
    result_.faces.reserve(2 * guess);
    const int g = std::clamp(static_cast<int>(std::sqrt(static_cast<double>(na))), 1, 1024);
    auto cell = [g](double x) { return std::clamp(static_cast<int>(x * g), 0, g - 1); };
    std::vector<std::array<double, 4>> abox(na);
    std::vector<int> start(g * g + 1, 0), items;
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (int f = 0; f < na; ++f) {
        const auto& t = a_.local[f];
        auto& bx = abox[f];
        bx = {a_.uv[t[0]].x(), a_.uv[t[0]].y(), a_.uv[t[0]].x(), a_.uv[t[0]].y()};
        for (int k = 1; k < 3; ++k) {
          bx[0] = std::min(bx[0], a_.uv[t[k]].x()), bx[1] = std::min(bx[1], a_.uv[t[k]].y());
          bx[2] = std::max(bx[2], a_.uv[t[k]].x()), bx[3] = std::max(bx[3], a_.uv[t[k]].y());
        }
        for (int j = cell(bx[1]); j <= cell(bx[3]); ++j)
          for (int i = cell(bx[0]); i <= cell(bx[2]); ++i) {
            if (pass == 0) ++start[j * g + i + 1];
            else items[fill[j * g + i]++] = f;
          }
      }
      if (pass == 0) {
        for (int c = 0; c < g * g; ++c) start[c + 1] += start[c];
        items.resize(start[g * g]);
      }
    }
    std::vector<int> stamp(na, -1), candidates;
    for (int fb = 0; fb < static_cast<int>(b_.local.size()); ++fb) {
      const auto& t = b_.local[fb];
      double bx[4] = {b_.uv[t[0]].x(), b_.uv[t[0]].y(), b_.uv[t[0]].x(), b_.uv[t[0]].y()};
      for (int k = 1; k < 3; ++k) {
        bx[0] = std::min(bx[0], b_.uv[t[k]].x()), bx[1] = std::min(bx[1], b_.uv[t[k]].y());
        bx[2] = std::max(bx[2], b_.uv[t[k]].x()), bx[3] = std::max(bx[3], b_.uv[t[k]].y());
      }
      candidates.clear();
      for (int j = cell(bx[1]); j <= cell(bx[3]); ++j)
        for (int i = cell(bx[0]); i <= cell(bx[2]); ++i)
          for (int c = start[j * g + i]; c < start[j * g + i + 1]; ++c) {
            const int fa = items[c];
            if (stamp[fa] == fb) continue;
            stamp[fa] = fb;
            const auto& ab = abox[fa];
            // Boxes that only touch cannot overlap with a positive area.
            if (ab[2] <= bx[0] || ab[0] >= bx[2] || ab[3] <= bx[1] || ab[1] >= bx[3]) continue;
            candidates.push_back(fa);
          }
      std::sort(candidates.begin(), candidates.end());
      for (int fa : candidates) overlay(fa, fb);
    }
    return std::move(result_);
  }

 private:
  // One vertex of an overlay polygon before it is numbered.
  struct Item {
    Key key;
    int kind;      // 0 A vertex, 1 B vertex, 2 crossing
    int ia, ib;    // kind 0: A corner index (ib: coinciding B corner or -1); kind 1: B corner (ia: -1);
                   // kind 2: A edge index ia (corner ia -> ia+1), B edge index ib
    int on_edge;   // kind 0: B edge index it lies on (or -1); kind 1: A edge index (or -1)
  };

  int vertex_of(const Item& it, int fa, int fb) {
    auto [pos, fresh] = index_.emplace(it.key, static_cast<int>(result_.vertices.size()));
    if (!fresh) return pos->second;
    const auto& ta = a_.local[fa];
    const auto& tb = b_.local[fb];
    const int cfa = a_.faces[fa], cfb = b_.faces[fb];
    std::array<Vec2, 3> qa, qb;
    std::array<Vec3, 3> pa, pb;
    for (int k = 0; k < 3; ++k) {
      qa[k] = a_.uv[ta[k]], qb[k] = b_.uv[tb[k]];
      pa[k] = ca_.mesh.positions[ca_.mesh.faces[cfa][k]];
      pb[k] = cb_.mesh.positions[cb_.mesh.faces[cfb][k]];
    }
    LocalVertex v;
    v.key = it.key;
    if (it.kind == 0) {
      v.uv = qa[it.ia];
      v.p = EPoint(v.uv.x(), v.uv.y());
      v.pa = pa[it.ia];
      if (it.ib >= 0) {
        v.pb = pb[it.ib];
        v.origin = Origin::Coincident;
      } else if (it.on_edge >= 0) {
        // Interpolate along the edge from its lower chart vertex id (the same from either face).
        int k0 = it.on_edge, k1 = (it.on_edge + 1) % 3;
        if (b_.vertex[tb[k1]] < b_.vertex[tb[k0]]) std::swap(k0, k1);
        v.pb = on_edge(v.uv, qb[k0], qb[k1], pb[k0], pb[k1]);
        v.origin = Origin::AOnBEdge;
      } else {
        v.pb = in_face(v.uv, qb, pb);
      }
    } else if (it.kind == 1) {
      v.uv = qb[it.ib];
      v.p = EPoint(v.uv.x(), v.uv.y());
      v.pb = pb[it.ib];
      if (it.on_edge >= 0) {
        int k0 = it.on_edge, k1 = (it.on_edge + 1) % 3;
        if (a_.vertex[ta[k1]] < a_.vertex[ta[k0]]) std::swap(k0, k1);
        v.pa = on_edge(v.uv, qa[k0], qa[k1], pa[k0], pa[k1]);
        v.origin = Origin::BOnAEdge;
      } else {
        v.origin = Origin::BInFace;
        v.pa = in_face(v.uv, qa, pa);
      }
    } else {
      // Both edges from their lower chart vertex id: the crossing is computed the same way
      // whichever of the (up to four) overlay polygons around it meets it first.
      int i0 = it.ia, i1 = (it.ia + 1) % 3, k0 = it.ib, k1 = (it.ib + 1) % 3;
      if (a_.vertex[ta[i1]] < a_.vertex[ta[i0]]) std::swap(i0, i1);
      if (b_.vertex[tb[k1]] < b_.vertex[tb[k0]]) std::swap(k0, k1);
      const EPoint A0(qa[i0].x(), qa[i0].y()), A1(qa[i1].x(), qa[i1].y());
      const EPoint B0(qb[k0].x(), qb[k0].y()), B1(qb[k1].x(), qb[k1].y());
      const Epeck::Vector_2 d = A1 - A0, e = B1 - B0, w = B0 - A0;
      const Epeck::FT den = d.x() * e.y() - d.y() * e.x();
      const Epeck::FT s = (w.x() * e.y() - w.y() * e.x()) / den;  // along the A edge
      v.p = A0 + d * s;
      v.uv = Vec2(std::clamp(rounded(v.p.x()), 0.0, 1.0), std::clamp(rounded(v.p.y()), 0.0, 1.0));
      // The parameters along both edges: in double when the edges cross at a fair angle, else exactly.
      const Vec2 dd = qa[i1] - qa[i0], ee = qb[k1] - qb[k0], ww = qb[k0] - qa[i0];
      const double dn = cross2(dd, ee);
      double sa, tb;
      if (std::abs(dn) > kWellConditioned * dd.norm() * ee.norm()) {
        sa = cross2(ww, ee) / dn, tb = cross2(ww, dd) / dn;
      } else {
        sa = rounded(s), tb = rounded((w.x() * d.y() - w.y() * d.x()) / den);
      }
      v.pa = lerp(pa[i0], pa[i1], std::clamp(sa, 0.0, 1.0));
      v.pb = lerp(pb[k0], pb[k1], std::clamp(tb, 0.0, 1.0));
      v.origin = Origin::Crossing;
    }
    result_.vertices.push_back(std::move(v));
    return pos->second;
  }

  void overlay(int fa, int fb) {
    const auto& ta = a_.local[fa];
    const auto& tb = b_.local[fb];
    std::array<Vec2, 3> pa, pb;
    for (int k = 0; k < 3; ++k) pa[k] = a_.uv[ta[k]], pb[k] = b_.uv[tb[k]];
    int sa[3][3], sb[3][3];  // sa[i][k]: A corner i against B edge k; sb[k][i]: B corner k against A edge i
    for (int k = 0; k < 3; ++k) {
      bool all_out = true;
      for (int i = 0; i < 3; ++i) {
        sa[i][k] = orient(pb[k], pb[(k + 1) % 3], pa[i]);
        all_out = all_out && sa[i][k] <= 0;
      }
      if (all_out) return;  // B edge k's line separates the triangles (or they touch along it)
    }
    for (int i = 0; i < 3; ++i) {
      bool all_out = true;
      for (int k = 0; k < 3; ++k) {
        sb[k][i] = orient(pa[i], pa[(i + 1) % 3], pb[k]);
        all_out = all_out && sb[k][i] <= 0;
      }
      if (all_out) return;
    }
    std::array<Item, 12> items;
    int n = 0;
    auto push = [&](const Item& it) {
      if (n == static_cast<int>(items.size()))
        throw InternalError("merge: more than 12 vertices in the overlap of two triangles");
      items[n++] = it;
    };
    const auto& va = a_.vertex;
    const auto& vb = b_.vertex;
    for (int i = 0; i < 3; ++i) {
      if (sa[i][0] < 0 || sa[i][1] < 0 || sa[i][2] < 0) continue;
      Item it{{0, va[ta[i]], -1, 0, 0}, 0, i, -1, -1};
      const int zeros = (sa[i][0] == 0) + (sa[i][1] == 0) + (sa[i][2] == 0);
      if (zeros == 2) {
        for (int k = 0; k < 3; ++k)
          if (sa[i][k] == 0 && sa[i][(k + 2) % 3] == 0) it.ib = k;
        it.key.y = vb[tb[it.ib]];
      } else if (zeros == 1) {
        for (int k = 0; k < 3; ++k)
          if (sa[i][k] == 0) it.on_edge = k;
      }
      push(it);
    }
    for (int k = 0; k < 3; ++k) {
      if (sb[k][0] < 0 || sb[k][1] < 0 || sb[k][2] < 0) continue;
      const int zeros = (sb[k][0] == 0) + (sb[k][1] == 0) + (sb[k][2] == 0);
      if (zeros == 2) continue;  // on an A corner: pushed with it
      Item it{{1, -1, vb[tb[k]], 0, 0}, 1, -1, k, -1};
      if (zeros == 1)
        for (int i = 0; i < 3; ++i)
          if (sb[k][i] == 0) it.on_edge = i;
      push(it);
    }
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) {
        const int i1 = (i + 1) % 3, k1 = (k + 1) % 3;
        if (sa[i][k] * sa[i1][k] < 0 && sb[k][i] * sb[k1][i] < 0) {
          const int x = va[ta[i]], y = va[ta[i1]], z = vb[tb[k]], w = vb[tb[k1]];
          push(Item{{2, std::min(x, y), std::max(x, y), std::min(z, w), std::max(z, w)}, 2, i, k, -1});
        }
      }
    if (n < 3) return;  // a point or a segment: no area
    std::array<int, 12> poly;
    for (int j = 0; j < n; ++j) poly[j] = vertex_of(items[j], fa, fb);
    // Counter-clockwise order around the first vertex (the polygon is convex): exact tests.
    const auto& V = result_.vertices;
    const EPoint& p0 = V[poly[0]].p;
    std::sort(poly.begin() + 1, poly.begin() + n, [&](int x, int y) {
      return CGAL::orientation(p0, V[x].p, V[y].p) == CGAL::LEFT_TURN;
    });
    for (int j = 0; j < n; ++j)
      if (CGAL::orientation(V[poly[j]].p, V[poly[(j + 1) % n]].p, V[poly[(j + 2) % n]].p) != CGAL::LEFT_TURN)
        throw InternalError("merge: the overlap of A chart face " + std::to_string(a_.faces[fa]) + " and B chart face " +
                            std::to_string(b_.faces[fb]) + " is not strictly convex (exact test)");
    ++result_.polygons;
    triangulate(poly, n, a_.faces[fa], b_.faces[fb]);
  }

  // Cuts the convex polygon into triangles: the triangulation that maximizes the smallest uv angle
  // (dynamic programming over its diagonals), or a fan from its first vertex.
  void triangulate(const std::array<int, 12>& poly, int n, int cfa, int cfb) {
    const auto& V = result_.vertices;
    auto emit = [&](int i, int j, int k) {
      // Positive by construction (a strictly convex polygon's vertices, in order); checked exactly.
      if (CGAL::orientation(V[poly[i]].p, V[poly[j]].p, V[poly[k]].p) != CGAL::LEFT_TURN)
        throw InternalError("merge: a triangle of the overlap of A chart face " + std::to_string(cfa) +
                            " and B chart face " + std::to_string(cfb) + " is not counter-clockwise (exact test)");
      result_.faces.push_back({poly[i], poly[j], poly[k]});
      result_.parent_a.push_back(cfa);
      result_.parent_b.push_back(cfb);
      result_.min_angle_uv.push_back(min_angle_degrees(V[poly[i]].uv, V[poly[j]].uv, V[poly[k]].uv));
    };
    if (n == 3 || !options_.improve_slivers) {
      for (int j = 1; j + 1 < n; ++j) emit(0, j, j + 1);
      return;
    }
    double best[12][12];
    int split[12][12];
    for (int len = 1; len < n; ++len)
      for (int i = 0; i + len < n; ++i) {
        const int j = i + len;
        if (len == 1) {
          best[i][j] = std::numeric_limits<double>::infinity();
          continue;
        }
        best[i][j] = -1;
        for (int k = i + 1; k < j; ++k) {
          const double q = std::min({min_angle_degrees(V[poly[i]].uv, V[poly[k]].uv, V[poly[j]].uv), best[i][k], best[k][j]});
          if (q > best[i][j]) best[i][j] = q, split[i][j] = k;
        }
      }
    std::vector<std::pair<int, int>> stack{{0, n - 1}};
    while (!stack.empty()) {
      const auto [i, j] = stack.back();
      stack.pop_back();
      if (j - i < 2) continue;
      const int k = split[i][j];
      emit(i, k, j);
      stack.push_back({k, j});
      stack.push_back({i, k});
    }
  }

  const dissect::Chart& ca_;
  const dissect::Chart& cb_;
  const PatchMesh& a_;
  const PatchMesh& b_;
  const MergeOptions& options_;
  PatchResult result_;
  std::unordered_map<Key, int, KeyHash> index_;
};

// ---- Patch sides: one order for both patches ---------------------------------------------------

// The side of the unit square a border point lies on (0: v = 0, 1: u = 1, 2: v = 1, 3: u = 0), or
// -1 for a corner or an interior point.
int side_of(const Vec2& uv) {
  const int n = (uv.y() == 0) + (uv.x() == 1) + (uv.y() == 1) + (uv.x() == 0);
  if (n != 1) return -1;
  return uv.y() == 0 ? 0 : uv.x() == 1 ? 1 : uv.y() == 1 ? 2 : 3;
}

// The coordinate along side s that increases counter-clockwise around the patch (exact).
double ccw_key(const Vec2& uv, int s) { return s == 0 ? uv.x() : s == 1 ? uv.y() : s == 2 ? -uv.x() : -uv.y(); }

// Where a chart vertex on a patch side sits: the patch and side of its lowest patch ("owner") and
// of the other one, with keys that increase the same way along the side in both.
struct SidePoint {
  int vertex;
  int p, sp, q, sq;
  double key_p, key_q;
  Vec2 uv_q;
};

// Side points (not corners) of a chart that are in exactly two patches.
std::vector<SidePoint> side_points(const dissect::Chart& c) {
  std::unordered_map<int, std::vector<std::pair<int, Vec2>>> uses;
  for (int f = 0; f < c.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const Vec2& uv = c.face_uv[f][k];
      if (side_of(uv) < 0) continue;
      auto& u = uses[c.mesh.faces[f][k]];
      if (std::none_of(u.begin(), u.end(), [&](const auto& x) { return x.first == c.face_patch[f]; }))
        u.push_back({c.face_patch[f], uv});
    }
  std::vector<SidePoint> out;
  for (auto& [v, u] : uses) {
    if (u.size() != 2) continue;
    if (u[1].first < u[0].first) std::swap(u[0], u[1]);
    const int sp = side_of(u[0].second), sq = side_of(u[1].second);
    if (sp < 0 || sq < 0) continue;
    // Both patches are counter-clockwise: they run along their common side in opposite directions.
    out.push_back({v, u[0].first, sp, u[1].first, sq, ccw_key(u[0].second, sp), -ccw_key(u[1].second, sq), u[1].second});
  }
  std::sort(out.begin(), out.end(), [](const SidePoint& x, const SidePoint& y) {
    return std::tie(x.p, x.sp, x.q, x.sq, x.key_p, x.vertex) < std::tie(y.p, y.sp, y.q, y.sq, y.key_p, y.vertex);
  });
  return out;
}

// Makes B's side points keep, in the second patch of each side, the place among A's side points
// that they have in the first (lower-index) patch: equal to the same A point, or strictly between
// the same two. The two patches compute a side's parameter separately, so a B point can tie with
// an A point in one and miss it by a rounding in the other (coinciding vertices: a mesh against
// itself refined, shared seeds and cut lines). Only B's uv in the second patch move, by a few
// units in the last place; positions never move. Returns the number of B points moved.
int reconcile_sides(const dissect::Chart& a, dissect::Chart& b) {
  const std::vector<SidePoint> sa = side_points(a), sb = side_points(b);
  auto group = [](const SidePoint& x) { return std::array<int, 4>{x.p, x.sp, x.q, x.sq}; };
  std::unordered_map<int, std::vector<std::pair<int, int>>> wedges;  // B vertex -> (face, corner) in its q
  int moved = 0;
  size_t ia = 0;
  for (size_t ib = 0; ib < sb.size();) {
    size_t jb = ib;
    while (jb < sb.size() && group(sb[jb]) == group(sb[ib])) ++jb;
    while (ia < sa.size() && group(sa[ia]) < group(sb[ib])) ++ia;
    size_t ja = ia;
    while (ja < sa.size() && group(sa[ja]) == group(sb[ib])) ++ja;
    // A's points on this side, by key in the first patch (their keys in the second follow).
    for (size_t k = ib; k < jb; ++k) {
      const SidePoint& x = sb[k];
      const auto lo = std::lower_bound(sa.begin() + ia, sa.begin() + ja, x.key_p,
                                       [](const SidePoint& s, double key) { return s.key_p < key; });
      double want_lo = -std::numeric_limits<double>::infinity(), want_hi = std::numeric_limits<double>::infinity();
      bool tie = false;
      if (lo != sa.begin() + ja && lo->key_p == x.key_p) {
        tie = true;
        want_lo = want_hi = lo->key_q;
      } else {
        if (lo != sa.begin() + ia) want_lo = std::prev(lo)->key_q;
        if (lo != sa.begin() + ja) want_hi = lo->key_q;
      }
      const bool ok = tie ? x.key_q == want_lo : (x.key_q > want_lo && x.key_q < want_hi);
      if (ok) continue;
      double key = tie ? want_lo : x.key_q;
      if (!tie) {
        if (!(key > want_lo)) key = std::nextafter(want_lo, want_hi);
        if (!(key < want_hi)) key = std::nextafter(want_hi, want_lo);
        if (!(key > want_lo && key < want_hi))
          throw SolverError("mesh B's chart vertex " + std::to_string(x.vertex) + " lies between two of mesh A's on "
                            "the side of patches " + std::to_string(x.p) + " and " + std::to_string(x.q) +
                            " in one and cannot be put between them in the other (no double in between)");
      }
      // Back from the key to the uv in the second patch: key = -ccw_key(uv, sq).
      Vec2 uv = x.uv_q;
      const double c = -key;
      if (x.sq == 0) uv.x() = c;
      else if (x.sq == 1) uv.y() = c;
      else if (x.sq == 2) uv.x() = -c;
      else uv.y() = -c;
      if (wedges.empty())
        for (int f = 0; f < b.mesh.num_faces(); ++f)
          for (int k2 = 0; k2 < 3; ++k2) wedges[b.mesh.faces[f][k2]].push_back({f, k2});
      for (const auto& [f, k2] : wedges[x.vertex])
        if (b.face_patch[f] == x.q) b.face_uv[f][k2] = uv;
      ++moved;
    }
    ib = jb;
  }
  return moved;
}

int patch_count(const dissect::Chart& chart) {
  int n = static_cast<int>(chart.patches.size());
  for (int p : chart.face_patch) n = std::max(n, p + 1);
  return n;
}

}  // namespace

void check_chart_uv(const dissect::Chart& chart, const std::string& name) {
  const int patches = patch_count(chart);
  const auto by = faces_by_patch(chart, patches);
  for (int p = 0; p < patches; ++p) build_patch(chart, by[p], p, name);
}

Merged merge_charts(const dissect::Chart& a, const dissect::Chart& b, const MergeOptions& options,
                    const Context& context) {
  const int patches = patch_count(a);
  if (patch_count(b) != patches)
    throw InvalidInput("the charts have " + std::to_string(patches) + " and " + std::to_string(patch_count(b)) +
                       " patches; qs-merge needs two charts of one dissection");
  if (a.patches.size() == b.patches.size())
    for (size_t p = 0; p < a.patches.size(); ++p)
      if (a.patches[p].name != b.patches[p].name)
        throw InvalidInput("patch " + std::to_string(p) + " is '" + a.patches[p].name + "' in mesh A and '" +
                           b.patches[p].name + "' in mesh B; qs-merge needs two charts of one dissection");
  // B's chart with its side points put in the same order among A's from both patches of a side.
  dissect::Chart b_sides = b;
  const int side_points_moved = reconcile_sides(a, b_sides);
  const auto by_a = faces_by_patch(a, patches), by_b = faces_by_patch(b, patches);

  std::vector<PatchResult> results(patches);
  // Every patch runs; the lowest patch's error is rethrown: deterministic.
  parallel_for(patches, options.threads, context, [&](int p) {
    const PatchMesh pa = build_patch(a, by_a[p], p, "mesh A");
    const PatchMesh pb = build_patch(b_sides, by_b[p], p, "mesh B");
    results[p] = PatchMerger(a, b_sides, pa, pb, options).run();
  });

  // Assembly in patch order: side vertices (A or B chart vertices on a patch side) are met in two
  // or more patches and take the first one's (patch, uv) and positions.
  Merged m;
  auto& st = m.stats;
  st.patches = patches;
  st.side_points_moved = side_points_moved;
  st.input_faces_a = a.mesh.num_faces();
  st.input_faces_b = b.mesh.num_faces();
  std::unordered_map<Key, int, KeyHash> global;
  std::vector<int> seen_a(a.mesh.num_vertices(), -1), seen_b(b.mesh.num_vertices(), -1);
  for (int p = 0; p < patches; ++p) {
    const PatchResult& r = results[p];
    std::vector<int> map(r.vertices.size());
    for (size_t i = 0; i < r.vertices.size(); ++i) {
      const LocalVertex& v = r.vertices[i];
      const int id = static_cast<int>(m.positions_a.size());
      auto [it, fresh] = global.emplace(v.key, id);
      map[i] = it->second;
      if (!fresh) continue;
      const int va = v.key.kind == 0 ? v.key.x : -1;
      const int vb = v.key.kind == 0 || v.key.kind == 1 ? v.key.y : -1;
      for (auto [seen, c, which] : {std::tuple{&seen_a, va, "A"}, std::tuple{&seen_b, vb, "B"}}) {
        if (c < 0) continue;
        if ((*seen)[c] >= 0)
          throw SolverError(std::string("chart vertex ") + std::to_string(c) + " of mesh " + which + " on a side of " +
                            patch_label(a, p) + " coincides with a vertex of the other mesh in one of the patches " +
                            "sharing the side but not in the other: the two meshes' side points are closer than the " +
                            "rounding of their uv (dissect again)");
        (*seen)[c] = id;
      }
      m.positions_a.push_back(v.pa);
      m.positions_b.push_back(v.pb);
      m.vertex_patch.push_back(p);
      m.vertex_uv.push_back(v.uv);
      m.vertex_a.push_back(va);
      m.vertex_b.push_back(vb);
      switch (v.origin) {
        case Origin::AOnBEdge: ++st.a_on_b_edge; break;
        case Origin::BOnAEdge: ++st.b_on_a_edge; break;
        case Origin::Crossing: ++st.crossings; break;
        default: break;
      }
      st.vertices_from_a += va >= 0;
      st.vertices_from_b += vb >= 0;
      st.coincident_vertices += va >= 0 && vb >= 0;
    }
    for (size_t f = 0; f < r.faces.size(); ++f) {
      m.faces.push_back({map[r.faces[f][0]], map[r.faces[f][1]], map[r.faces[f][2]]});
      m.face_patch.push_back(p);
      m.face_parent_a.push_back(r.parent_a[f]);
      m.face_parent_b.push_back(r.parent_b[f]);
      st.slivers_uv += r.min_angle_uv[f] < options.sliver_degrees;
      st.min_angle_uv = std::min(st.min_angle_uv, r.min_angle_uv[f]);
    }
    st.overlay_polygons += r.polygons;
  }
  for (auto [seen, which] : {std::pair{&seen_a, "A"}, std::pair{&seen_b, "B"}})
    for (size_t v = 0; v < seen->size(); ++v)
      if ((*seen)[v] < 0)
        throw InternalError(std::string("merge: chart vertex ") + std::to_string(v) + " of mesh " + which +
                            " is in no merged face");

  // The merged mesh must be closed and manifold with V - E + F = 2: every edge in exactly two
  // faces, once in each direction. A violation means the two patches along a side disagreed.
  {
    std::vector<std::array<int, 3>> edges;
    edges.reserve(3 * m.faces.size());
    for (const Tri& t : m.faces)
      for (int k = 0; k < 3; ++k) {
        const int x = t[k], y = t[(k + 1) % 3];
        edges.push_back({std::min(x, y), std::max(x, y), x < y ? 1 : -1});
      }
    std::sort(edges.begin(), edges.end());
    long long unique = 0;
    for (size_t i = 0; i < edges.size();) {
      size_t j = i;
      int sum = 0;
      while (j < edges.size() && edges[j][0] == edges[i][0] && edges[j][1] == edges[i][1]) sum += edges[j++][2];
      if (j - i != 2 || sum != 0) {
        const int x = edges[i][0], y = edges[i][1];
        throw SolverError("the merged mesh is not closed and manifold at its edge (" + std::to_string(x) + ", " +
                          std::to_string(y) + ") in " + patch_label(a, m.vertex_patch[x]) + ": " +
                          std::to_string(j - i) + " faces use it; the two patches sharing a side ordered its points "
                          "differently (their uv differ by less than the rounding of the side parameter)");
      }
      ++unique;
      i = j;
    }
    const long long chi = static_cast<long long>(m.positions_a.size()) - unique + static_cast<long long>(m.faces.size());
    if (chi != 2)
      throw SolverError("the merged mesh has V - E + F = " + std::to_string(chi) + " (expected 2: genus 0)");
  }

  // Quality: slivers at t = 0 and t = 1, and the inputs' own for comparison.
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const Tri& t = m.faces[f];
    const double qa = min_angle_degrees(m.positions_a[t[0]], m.positions_a[t[1]], m.positions_a[t[2]]);
    const double qb = min_angle_degrees(m.positions_b[t[0]], m.positions_b[t[1]], m.positions_b[t[2]]);
    st.slivers_a += !(qa >= options.sliver_degrees);
    st.slivers_b += !(qb >= options.sliver_degrees);
    if (qa == qa) st.min_angle_a = std::min(st.min_angle_a, qa);
    if (qb == qb) st.min_angle_b = std::min(st.min_angle_b, qb);
    auto normal = [](const std::vector<Vec3>& P, const Tri& t) { return (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]); };
    for (auto [P, chart, parent, thin, off] :
         {std::tuple{&m.positions_a, &a, m.face_parent_a[f], &st.thin_faces_a, &st.normal_disagreements_a},
          std::tuple{&m.positions_b, &b, m.face_parent_b[f], &st.thin_faces_b, &st.normal_disagreements_b}}) {
      const Vec3 n = normal(*P, t), np = normal(chart->mesh.positions, chart->mesh.faces[parent]);
      if (!(n.norm() > kThinFace * np.norm())) ++*thin;
      else if (!(n.dot(np) > 0)) ++*off;
    }
  }
  for (auto [chart, count] : {std::pair{&a, &st.input_slivers_a}, std::pair{&b, &st.input_slivers_b}})
    for (const Tri& t : chart->mesh.faces) {
      const auto& P = chart->mesh.positions;
      *count += !(min_angle_degrees(P[t[0]], P[t[1]], P[t[2]]) >= options.sliver_degrees);
    }
  return m;
}

}  // namespace qs::merge
