// Geodesic seed curves: funnel algorithm in an unfolded face strip plus vertex flips (Martinez,
// Velho, Carvalho 2005), then the curve cut into the mesh.

#include "qs/dissect/geodesic_loop.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/dissect/seed_routing_detail.h"

namespace qs::dissect {
namespace {

int rotate_cw(const CutMesh& cm, int h) { return CutMesh::next(cm.opposite(h)); }

/// The half-edge of face f leaving v, or -1 when v is not a corner of f.
int out_of(const CutMesh& cm, int f, int v) {
  for (int k = 0; k < 3; ++k)
    if (cm.face(f)[k] == v) return 3 * f + k;
  return -1;
}

bool has_vertex(const CutMesh& cm, int f, int v) { return out_of(cm, f, v) >= 0; }

/// The third corner of the triangle with edge A->B (2D, unfolded) whose 3D distances to a and b
/// are da and db, placed left of A->B (the face that has A->B as a counter-clockwise edge).
Vec2 place_left(const Vec2& A, const Vec2& B, double da, double db) {
  const Vec2 e = B - A;
  const double len = e.norm();
  if (!(len > 0)) return A + Vec2(0, da);
  const Vec2 ux = e / len, uy(-ux.y(), ux.x());
  const double x = (da * da - db * db + len * len) / (2 * len);
  const double y = std::sqrt(std::max(0.0, da * da - x * x));
  return A + x * ux + y * uy;
}

/// Where a curve meets portal j: a vertex, or the point (1-t) a + t b of edge a-b.
struct Crossing {
  int vertex = -1;
  int a = -1, b = -1;
  double t = 0;
};

/// The shortest path from s to d inside a face strip (consecutive faces share an edge).
struct Funnel {
  bool ok = false;
  std::string why;
  double length = 0;
  std::vector<int> corner_vertex;  ///< inner corners (the vertices the path bends around)
  std::vector<int> corner_portal;  ///< the portal (1..n) at which each was found
  std::vector<Crossing> crossing;  ///< per portal 1..n (index 0 unused)
};

Funnel run_funnel(const CutMesh& cm, const std::vector<int>& faces, int s, int d) {
  Funnel out;
  const int n = static_cast<int>(faces.size()) - 1;  // portals 1..n
  const auto& P = cm.positions();
  auto dist = [&](int a, int b) { return (P[a] - P[b]).norm(); };
  if (n == 0) {
    out.ok = has_vertex(cm, faces[0], s) && has_vertex(cm, faces[0], d);
    out.length = dist(s, d);
    out.crossing.resize(1);
    if (!out.ok) out.why = "the strip of one face does not hold both ends";
    return out;
  }
  // Portals with their ends unfolded into the plane, face by face.
  std::vector<Vec2> L(n + 2), R(n + 2);
  std::vector<int> Lid(n + 2), Rid(n + 2);
  std::vector<int> he(n + 1, -1);
  for (int j = 1; j <= n; ++j) {
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * faces[j - 1] + k;
      if (CutMesh::face_of(cm.opposite(h)) == faces[j]) he[j] = h;
    }
    if (he[j] < 0) {
      out.why = "faces " + std::to_string(faces[j - 1]) + " and " + std::to_string(faces[j]) + " of the strip are not adjacent";
      return out;
    }
    Rid[j] = cm.tail(he[j]);
    Lid[j] = cm.head(he[j]);
  }
  R[1] = Vec2(0, 0);
  L[1] = Vec2(dist(Rid[1], Lid[1]), 0);
  for (int j = 1; j < n; ++j) {
    const int hh = cm.opposite(he[j]);  // L_j -> R_j in face j
    const int c = cm.head(CutMesh::next(hh));
    const Vec2 cp = place_left(L[j], R[j], dist(Lid[j], c), dist(Rid[j], c));
    const int nx = he[j + 1];
    auto pos_of = [&](int v) { return v == Lid[j] ? L[j] : v == Rid[j] ? R[j] : cp; };
    if (nx == CutMesh::next(hh) || nx == CutMesh::prev(hh)) {
      Rid[j + 1] = cm.tail(nx);
      Lid[j + 1] = cm.head(nx);
      R[j + 1] = pos_of(Rid[j + 1]);
      L[j + 1] = pos_of(Lid[j + 1]);
    } else {
      out.why = "the strip leaves face " + std::to_string(faces[j]) + " through the edge it entered by";
      return out;
    }
  }
  // The ends.
  Vec2 S, D;
  if (s == Rid[1]) S = R[1];
  else if (s == Lid[1]) S = L[1];
  else {
    const int c = cm.head(CutMesh::next(he[1]));
    if (c != s) {
      out.why = "the start is not a corner of the first face";
      return out;
    }
    S = place_left(R[1], L[1], dist(Rid[1], s), dist(Lid[1], s));
  }
  if (d == Rid[n]) D = R[n];
  else if (d == Lid[n]) D = L[n];
  else {
    const int hh = cm.opposite(he[n]);
    const int c = cm.head(CutMesh::next(hh));
    if (c != d) {
      out.why = "the end is not a corner of the last face";
      return out;
    }
    D = place_left(L[n], R[n], dist(Lid[n], d), dist(Rid[n], d));
  }
  L[0] = R[0] = S;
  Lid[0] = Rid[0] = s;
  L[n + 1] = R[n + 1] = D;
  Lid[n + 1] = Rid[n + 1] = d;

  // Simple stupid funnel (Mononen), cross products positive to the left.
  std::vector<Vec2> cpos{S};
  std::vector<int> cidx{0}, cvert{s};
  Vec2 apex = S, left = S, right = S;
  int apex_i = 0, left_i = 0, right_i = 0;
  // The funnel's side point `pi` becomes the new apex (a corner of the path); the walk restarts there.
  auto restart_at = [&](int pi, const Vec2& p, int vertex, int& i) {
    apex = p;
    apex_i = pi;
    cpos.push_back(apex);
    cidx.push_back(apex_i);
    cvert.push_back(vertex);
    left = right = apex;
    left_i = right_i = apex_i;
    i = apex_i;
  };
  for (int i = 1; i <= n + 1; ++i) {
    const Vec2& l = L[i];
    const Vec2& r = R[i];
    if (cross2(right - apex, r - apex) >= 0) {
      if (apex == right || cross2(left - apex, r - apex) < 0) {
        right = r;
        right_i = i;
      } else {
        restart_at(left_i, left, Lid[left_i], i);
        continue;
      }
    }
    if (cross2(left - apex, l - apex) <= 0) {
      if (apex == left || cross2(right - apex, l - apex) > 0) {
        left = l;
        left_i = i;
      } else {
        restart_at(right_i, right, Rid[right_i], i);
        continue;
      }
    }
  }
  cpos.push_back(D);
  cidx.push_back(n + 1);
  cvert.push_back(d);
  for (size_t a = 1; a < cpos.size(); ++a) out.length += (cpos[a] - cpos[a - 1]).norm();
  for (size_t a = 1; a + 1 < cpos.size(); ++a) {
    out.corner_vertex.push_back(cvert[a]);
    out.corner_portal.push_back(cidx[a]);
  }
  // Crossings: portal j lies between corners a and a+1 with cidx[a] <= j < cidx[a+1].
  out.crossing.resize(n + 1);
  size_t a = 0;
  for (int j = 1; j <= n; ++j) {
    while (a + 1 < cidx.size() && cidx[a + 1] <= j) ++a;
    Crossing& x = out.crossing[j];
    const int ca = cvert[a], cb = a + 1 < cvert.size() ? cvert[a + 1] : d;
    if (Rid[j] == ca || Lid[j] == ca) {
      x.vertex = ca;
    } else if (Rid[j] == cb || Lid[j] == cb) {
      x.vertex = cb;
    } else {
      const Vec2 dir = cpos[a + 1] - cpos[a];
      const double den = cross2(L[j] - R[j], dir);
      double t = std::abs(den) > 0 ? cross2(cpos[a] - R[j], dir) / den : 0.5;
      if (!std::isfinite(t)) t = 0.5;
      x.a = Rid[j];
      x.b = Lid[j];
      x.t = std::clamp(t, 0.0, 1.0);
    }
  }
  out.ok = true;
  return out;
}

double angle_at(const CutMesh& cm, int f, int v) {
  const int h = out_of(cm, f, v);
  const Vec3& p = cm.position(v);
  const Vec3 e1 = cm.position(cm.head(h)) - p;
  const Vec3 e2 = cm.position(cm.tail(CutMesh::prev(h))) - p;
  return std::atan2(e1.cross(e2).norm(), e1.dot(e2));
}

/// The faces left of an edge path (the fans at its inner vertices), in order along it.
std::optional<std::vector<int>> left_strip(const CutMesh& cm, const std::vector<int>& path) {
  std::vector<int> strip;
  const int m = static_cast<int>(path.size()) - 1;
  for (int k = 1; k < m; ++k) {
    const int v = path[k];
    const int h_out = cm.find_halfedge(v, path[k + 1]);
    const int h_back = cm.find_halfedge(v, path[k - 1]);
    if (h_out < 0 || h_back < 0) return std::nullopt;
    std::vector<int> fan;
    int h = h_out;
    for (int guard = 0; h != h_back; ++guard) {
      if (guard > 100000) return std::nullopt;
      fan.push_back(CutMesh::face_of(h));
      h = cm.rotate_ccw(h);
    }
    for (auto it = fan.rbegin(); it != fan.rend(); ++it)
      if (strip.empty() || strip.back() != *it) strip.push_back(*it);
  }
  return strip;
}

struct Straightened {
  bool ok = false;
  std::string why;
  std::vector<int> path;  ///< vertex ids of cm after insertion
};

/// Straightens path (an edge path of cm) and cuts it into cm. On failure cm may be cut in part:
/// the caller rolls it back to its checkpoint.
Straightened straighten_one(CutMesh& cm, const std::vector<int>& path, const std::vector<char>& blocked,
                            const GeodesicLoopOptions& opt) {
  Straightened res;
  const int s = path.front(), d = path.back();
  if (path.size() <= 2) {
    res.ok = true;
    res.path = path;
    return res;
  }
  auto strip_opt = left_strip(cm, path);
  if (!strip_opt) {
    res.why = "the edge path is not a path of the mesh";
    return res;
  }
  std::vector<int> strip = std::move(*strip_opt);
  std::vector<char> in_strip(cm.num_faces(), 0);
  for (int f : strip) {
    if (in_strip[f]) {
      res.why = "the faces beside it overlap (face " + std::to_string(f) + " twice)";
      return res;
    }
    in_strip[f] = 1;
  }
  Funnel fun = run_funnel(cm, strip, s, d);
  if (!fun.ok) {
    res.why = fun.why;
    return res;
  }
  // Flips: move the strip to the other side of a vertex the path bends around when the angle there
  // is below pi and the path gets shorter.
  const int limit = opt.max_rounds * static_cast<int>(path.size());
  int flips = 0;
  for (size_t a = 0; a < fun.corner_vertex.size() && flips < limit;) {
    const int v = fun.corner_vertex[a];
    const int k = fun.corner_portal[a];
    bool accepted = false;
    if (!blocked[v] && k >= 1 && k < static_cast<int>(strip.size())) {
      const int last = static_cast<int>(strip.size()) - 1;
      int i1 = k - 1, i2 = k;
      while (i1 > 0 && has_vertex(cm, strip[i1 - 1], v)) --i1;
      while (i2 < last && has_vertex(cm, strip[i2 + 1], v)) ++i2;
      const int h1 = out_of(cm, strip[i1], v);
      std::vector<int> other;
      bool fan_ok = h1 >= 0 && i2 > i1;
      if (fan_ok) {
        const bool ccw = CutMesh::face_of(cm.rotate_ccw(h1)) == strip[i1 + 1];
        const bool cw = CutMesh::face_of(rotate_cw(cm, h1)) == strip[i1 + 1];
        if (ccw == cw) fan_ok = false;
        int h = h1;
        for (int guard = 0; fan_ok; ++guard) {
          h = ccw ? rotate_cw(cm, h) : cm.rotate_ccw(h);
          const int f = CutMesh::face_of(h);
          if (f == strip[i2]) break;
          if (in_strip[f] || guard > 100000) fan_ok = false;
          else other.push_back(f);
        }
      }
      double angle = 0;
      for (int f : other) angle += angle_at(cm, f, v);
      if (fan_ok && angle < M_PI - 1e-12) {
        std::vector<int> cand(strip.begin(), strip.begin() + i1 + 1);
        cand.insert(cand.end(), other.begin(), other.end());
        cand.insert(cand.end(), strip.begin() + i2, strip.end());
        Funnel f2 = run_funnel(cm, cand, s, d);
        if (f2.ok && f2.length < fun.length * (1 - 1e-12)) {
          for (int i = i1 + 1; i < i2; ++i) in_strip[strip[i]] = 0;
          for (int f : other) in_strip[f] = 1;
          strip = std::move(cand);
          fun = std::move(f2);
          accepted = true;
          ++flips;
        }
      }
    }
    if (accepted) a = a > 0 ? a - 1 : 0;
    else ++a;
  }
  for (int v : fun.corner_vertex)
    if (blocked[v]) {
      res.why = "its shortest form touches vertex " + std::to_string(v) + " (a seed, feature or another curve)";
      return res;
    }
  // The curve as vertices and edge points, snapped near edge ends.
  struct Item {
    int vertex = -1;
    int a = -1, b = -1;
    double t = 0;
  };
  std::vector<Item> items;
  auto push_vertex = [&](int v) {
    if (items.empty() || items.back().vertex != v) items.push_back({v, -1, -1, 0});
  };
  push_vertex(s);
  for (size_t j = 1; j < fun.crossing.size(); ++j) {
    const Crossing& x = fun.crossing[j];
    if (x.vertex >= 0) {
      push_vertex(x.vertex);
      continue;
    }
    if (x.t <= opt.snap && !blocked[x.a]) push_vertex(x.a);
    else if (x.t >= 1 - opt.snap && !blocked[x.b]) push_vertex(x.b);
    else items.push_back({-1, x.a, x.b, std::clamp(x.t, 1e-3, 1 - 1e-3)});
  }
  push_vertex(d);
  {
    std::vector<int> seen;
    for (const Item& it : items)
      if (it.vertex >= 0) seen.push_back(it.vertex);
    std::sort(seen.begin(), seen.end());
    if (std::adjacent_find(seen.begin(), seen.end()) != seen.end()) {
      res.why = "its straightened form passes a vertex twice";
      return res;
    }
    for (size_t i = 1; i + 1 < items.size(); ++i)
      if (items[i].vertex >= 0 && blocked[items[i].vertex]) {
        res.why = "its straightened form touches vertex " + std::to_string(items[i].vertex);
        return res;
      }
  }
  // Cut it in.
  std::vector<int> out{s};
  for (size_t i = 1; i < items.size(); ++i) {
    const Item& it = items[i];
    int v = it.vertex;
    if (v < 0) {
      const int h = cm.find_halfedge(it.a, it.b);
      if (h < 0) {
        res.why = "edge " + std::to_string(it.a) + "-" + std::to_string(it.b) + " is crossed twice";
        return res;
      }
      v = cm.split_edge(h, it.t);
    }
    if (cm.find_halfedge(out.back(), v) < 0) {
      res.why = "consecutive points " + std::to_string(out.back()) + " and " + std::to_string(v) +
                " of the straightened curve do not share a face";
      return res;
    }
    out.push_back(v);
  }
  res.ok = true;
  res.path = std::move(out);
  return res;
}

double path_length_of(const std::vector<Vec3>& P, const std::vector<int>& p) {
  double l = 0;
  for (size_t k = 1; k < p.size(); ++k) l += (P[p[k]] - P[p[k - 1]]).norm();
  return l;
}

void check_options(const GeodesicLoopOptions& options, int num_vertices) {
  if (!(options.snap >= 0 && options.snap < 0.5))
    throw InvalidInput("straighten_seed_loop: options.snap must be in [0, 0.5) (got " + std::to_string(options.snap) + ")");
  if (options.max_rounds < 0)
    throw InvalidInput("straighten_seed_loop: options.max_rounds must be >= 0");
  for (int v : options.avoid)
    if (v < 0 || v >= num_vertices)
      throw InvalidInput("straighten_seed_loop: vertex to avoid " + std::to_string(v) + " is out of range");
}

// The straightening of `loop` on the cut mesh `cm` (reset first: what a build from its faces gives).
GeodesicLoop straighten_on(CutMesh cm, const SeedLoop& loop, const GeodesicLoopOptions& options,
                           const Context& context) {
  check_options(options, cm.num_vertices());
  cm.reset();
  std::string why;
  const std::vector<int> labels = routing::label_faces(cm, loop, why);
  if (labels.empty()) throw InvalidInput("seed loop does not cut the mesh into two patches: " + why);
  TriMesh mesh = cm.to_trimesh();
  const std::vector<int> sides_before = sides_of_vertices(mesh, labels, options.avoid);
  GeodesicLoop result;
  result.loop = loop;
  for (int i = 0; i < 4; ++i) result.length_before[i] = result.length_after[i] = path_length_of(mesh.positions, loop.paths[i]);
  const int input_vertices = mesh.num_vertices();
  result.mesh = std::move(mesh);
  SeedLoop cur = loop;
  for (int i = 0; i < 4; ++i) {
    context.check_cancel();
    std::vector<char> blocked(cm.num_vertices(), 0);
    for (int v : options.avoid) blocked[v] = 1;
    for (int j = 0; j < 4; ++j) {
      if (j != i && j != (i + 1) % 4) blocked[loop.seeds[j]] = 1;
      if (j == i) continue;
      for (size_t k = 1; k + 1 < cur.paths[j].size(); ++k) blocked[cur.paths[j][k]] = 1;
    }
    cm.checkpoint();
    Straightened st = straighten_one(cm, cur.paths[i], blocked, options);
    if (!st.ok) {
      cm.rollback();
      result.why[i] = "curve " + std::to_string(i) + " kept as an edge path: " + st.why;
      continue;
    }
    // The other curves must still be edge paths (a crossing never splits one of their edges).
    bool intact = true;
    for (int j = 0; j < 4 && intact; ++j)
      if (j != i)
        for (size_t k = 1; k < cur.paths[j].size() && intact; ++k)
          intact = cm.find_halfedge(cur.paths[j][k - 1], cur.paths[j][k]) >= 0;
    if (!intact) {
      cm.rollback();
      result.why[i] = "curve " + std::to_string(i) + " kept as an edge path: its straightened form cuts another curve";
      continue;
    }
    cm.commit();
    cur.paths[i] = std::move(st.path);
    result.straightened[i] = true;
  }
  TriMesh refined = cm.to_trimesh();
  // The loop must still cut the mesh in two with every avoided vertex on its old side.
  std::vector<int> face_patches = routing::label_faces(cm, cur, why);
  if (face_patches.empty())
    why = "seed loop does not cut the mesh into two patches: " + why;
  else if (sides_of_vertices(refined, face_patches, options.avoid) != sides_before)
    why = "a feature changed sides";
  if (!why.empty()) {
    for (int i = 0; i < 4; ++i) {
      result.straightened[i] = false;
      result.why[i] = "the straightened loop was rejected (" + why + "); edge paths kept";
    }
    return result;
  }
  result.inserted_vertices = refined.num_vertices() - input_vertices;
  result.mesh = std::move(refined);
  result.loop = std::move(cur);
  if (result.any_straightened()) {
    result.face_patches = std::move(face_patches);
    cm.reset();
    result.cut = std::move(cm);
  }
  for (int i = 0; i < 4; ++i) result.length_after[i] = path_length_of(result.mesh.positions, result.loop.paths[i]);
  return result;
}

}  // namespace

GeodesicLoop straighten_seed_loop(const TriMesh& mesh, const SeedLoop& loop, const GeodesicLoopOptions& options,
                                  const Context& context) {
  return straighten_on(CutMesh(mesh), loop, options, context);
}

GeodesicLoop straighten_seed_loop(const CutMesh& mesh, const SeedLoop& loop, const GeodesicLoopOptions& options,
                                  const Context& context) {
  return straighten_on(mesh, loop, options, context);
}

}  // namespace qs::dissect
