#include "qs/bake/split_mesh.h"

#include <cmath>
#include <string>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"

namespace qs::bake {

namespace {

struct Site {
  int patch;
  Vec2 uv;
};

// Point at fraction t along side k of the unit square (corner k to corner k+1).
Vec2 side_point(int k, double t) {
  switch (k) {
    case 0: return {t, 0.0};
    case 1: return {1.0, t};
    case 2: return {1.0 - t, 1.0};
    default: return {0.0, 1.0 - t};
  }
}

const Vec2 kCorner[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};

}  // namespace

std::vector<Vec3> vertex_normals(const TriMesh& mesh) {
  const int nv = mesh.num_vertices();
  std::vector<Vec3> angle_sum(nv, Vec3::Zero()), area_sum(nv, Vec3::Zero());
  for (const Tri& t : mesh.faces) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const Vec3 n = (b - a).cross(c - a);
    const double len = n.norm();
    if (!(len > 0) || !std::isfinite(len)) continue;
    for (int k = 0; k < 3; ++k) area_sum[t[k]] += n;
    const Vec3 unit = n / len;
    for (int k = 0; k < 3; ++k) {
      const Vec3& p = mesh.positions[t[k]];
      const Vec3 e1 = mesh.positions[t[(k + 1) % 3]] - p, e2 = mesh.positions[t[(k + 2) % 3]] - p;
      if (e1.squaredNorm() == 0 || e2.squaredNorm() == 0) continue;
      angle_sum[t[k]] += unit * std::atan2(e1.cross(e2).norm(), e1.dot(e2));
    }
  }
  std::vector<Vec3> normals(nv);
  for (int v = 0; v < nv; ++v) {
    const double la = angle_sum[v].norm(), lb = area_sum[v].norm();
    normals[v] = la > 0 ? Vec3(angle_sum[v] / la) : lb > 0 ? Vec3(area_sum[v] / lb) : Vec3(0, 0, 1);
  }
  return normals;
}

SplitMesh split_by_patch(const remesh::SemiRegularConnectivity& c, const std::vector<Vec3>& positions,
                         const remesh::BaseTopology& topology) {
  const int nv = c.num_vertices(), np = topology.num_patches();
  if (static_cast<int>(positions.size()) != nv)
    throw InvalidInput("bake: " + std::to_string(positions.size()) + " positions for a remesh of " + std::to_string(nv) +
                       " vertices");
  if (static_cast<int>(c.vertex_uv.size()) != nv)
    throw InvalidInput("bake: the remesh has " + std::to_string(c.vertex_uv.size()) + " vertex (u,v) for " +
                       std::to_string(nv) + " vertices");
  if (c.num_patches != np)
    throw InvalidInput("bake: the remesh has " + std::to_string(c.num_patches) + " patches, its dissection " +
                       std::to_string(np) + " (was it made from another dissection?)");

  // Base vertex -> every (patch, corner) around it.
  std::vector<std::vector<std::pair<int, int>>> corners_of(topology.num_vertices);
  for (int p = 0; p < np; ++p)
    for (int k = 0; k < 4; ++k) corners_of[topology.quads[p][k]].push_back({p, k});

  const double eps = 1e-12;
  auto sites = [&](int v, std::vector<Site>& out) {
    out.clear();
    const int p = c.vertex_patch[v];
    const Vec2 uv = c.vertex_uv[v];
    if (p < 0 || p >= np || !(uv.x() >= 0 && uv.x() <= 1 && uv.y() >= 0 && uv.y() <= 1))
      throw InvalidInput("bake: remesh vertex " + std::to_string(v) + " has (patch, u, v) out of range");
    const bool u0 = uv.x() <= eps, u1 = uv.x() >= 1 - eps, v0 = uv.y() <= eps, v1 = uv.y() >= 1 - eps;
    if ((u0 || u1) && (v0 || v1)) {
      const int k = v0 ? (u0 ? 0 : 1) : (u1 ? 2 : 3);
      for (const auto& [q, kq] : corners_of[topology.quads[p][k]]) out.push_back({q, kCorner[kq]});
    } else if (u0 || u1 || v0 || v1) {
      const int k = v0 ? 0 : u1 ? 1 : v1 ? 2 : 3;
      const double t = k == 0 ? uv.x() : k == 1 ? uv.y() : k == 2 ? 1.0 - uv.x() : 1.0 - uv.y();
      out.push_back({p, side_point(k, t)});
      const remesh::PatchSide twin = topology.twin(p, k);
      out.push_back({twin.patch, side_point(twin.side, 1.0 - t)});
    } else {
      out.push_back({p, uv});
    }
  };

  SplitMesh m;
  const int nf = c.num_faces();
  m.faces.resize(nf);
  m.face_patch.resize(nf);
  std::vector<std::vector<std::pair<int, int>>> copies(nv);  // remesh vertex -> (patch, split id)
  std::vector<Site> s[3];
  for (int f = 0; f < nf; ++f) {
    const Tri& t = c.faces[f];
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || t[k] >= nv)
        throw InvalidInput("bake: remesh face " + std::to_string(f) + " has vertex id " + std::to_string(t[k]) +
                           " out of range");
      sites(t[k], s[k]);
    }
    int best = -1;
    double best_area = 0;
    Vec2 best_uv[3];
    for (const Site& a : s[0])
      for (const Site& b : s[1]) {
        if (b.patch != a.patch) continue;
        for (const Site& d : s[2]) {
          if (d.patch != a.patch) continue;
          const double area = cross2(b.uv - a.uv, d.uv - a.uv);
          if (area > best_area) {
            best = a.patch;
            best_area = area;
            best_uv[0] = a.uv, best_uv[1] = b.uv, best_uv[2] = d.uv;
          }
        }
      }
    if (best < 0)
      throw InvalidInput("bake: remesh face " + std::to_string(f) + " (vertices " + std::to_string(t[0]) + ", " +
                         std::to_string(t[1]) + ", " + std::to_string(t[2]) +
                         ") lies in no patch with a counter-clockwise (u,v) triangle; the remesh and the "
                         "dissection do not match");
    m.face_patch[f] = best;
    for (int k = 0; k < 3; ++k) {
      int id = -1;
      for (const auto& [q, sid] : copies[t[k]])
        if (q == best) id = sid;
      if (id < 0) {
        id = m.num_vertices();
        copies[t[k]].push_back({best, id});
        m.positions.push_back(positions[t[k]]);
        m.source_vertex.push_back(t[k]);
        m.vertex_patch.push_back(best);
        m.vertex_uv.push_back(best_uv[k]);
      }
      m.faces[f][k] = id;
    }
  }

  const std::vector<Vec3> n = vertex_normals(TriMesh{positions, c.faces});
  const int ns = m.num_vertices();
  m.normals.resize(ns);
  for (int i = 0; i < ns; ++i) m.normals[i] = n[m.source_vertex[i]];

  // dP/du and dP/dv per face, weighted by the (u,v) area, summed per split vertex.
  std::vector<Vec3> tu(ns, Vec3::Zero()), tv(ns, Vec3::Zero());
  for (int f = 0; f < nf; ++f) {
    const Tri& t = m.faces[f];
    const Vec3 e1 = m.positions[t[1]] - m.positions[t[0]], e2 = m.positions[t[2]] - m.positions[t[0]];
    const Vec2 d1 = m.vertex_uv[t[1]] - m.vertex_uv[t[0]], d2 = m.vertex_uv[t[2]] - m.vertex_uv[t[0]];
    const Vec3 a = 0.5 * (e1 * d2.y() - e2 * d1.y()), b = 0.5 * (e2 * d1.x() - e1 * d2.x());
    for (int k = 0; k < 3; ++k) tu[t[k]] += a, tv[t[k]] += b;
  }
  m.tangents.resize(ns);
  for (int i = 0; i < ns; ++i) {
    const Vec3& N = m.normals[i];
    Vec3 T = tu[i] - N * N.dot(tu[i]);
    if (!(T.norm() > 1e-12 * (tu[i].norm() + tv[i].norm()) && T.norm() > 0)) {
      T = tv[i].cross(N);  // fall back on dP/dv, else any direction perpendicular to N
      if (!(T.norm() > 0)) T = std::abs(N.x()) < 0.9 ? Vec3(N.cross(Vec3::UnitX())) : Vec3(N.cross(Vec3::UnitY()));
      T -= N * N.dot(T);
    }
    T.normalize();
    const double w = N.cross(T).dot(tv[i]) >= 0 ? 1.0 : -1.0;
    m.tangents[i] = {T.x(), T.y(), T.z(), w};
  }
  return m;
}

}  // namespace qs::bake
