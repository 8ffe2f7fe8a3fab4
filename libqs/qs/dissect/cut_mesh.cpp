#include "qs/dissect/cut_mesh.h"

#include <algorithm>
#include <cstdint>
#include <string>

#include "qs/core/error.h"

namespace qs::dissect {

CutMesh::CutMesh(const TriMesh& mesh) : positions_(mesh.positions), faces_(mesh.faces) {
  const int nh = 3 * num_faces();
  opp_.assign(nh, -1);
  vertex_halfedge_.assign(num_vertices(), -1);
  face_patch_.assign(num_faces(), 0);
  // Pair half-edges by sorting (min, max, h) keys.
  std::vector<std::pair<std::uint64_t, int>> keys(nh);
  for (int h = 0; h < nh; ++h) {
    const std::uint64_t a = tail(h), b = head(h);
    keys[h] = {(std::min(a, b) << 32) | std::max(a, b), h};
    vertex_halfedge_[a] = h;
  }
  std::sort(keys.begin(), keys.end());
  for (int i = 0; i < nh;) {
    int j = i;
    while (j < nh && keys[j].first == keys[i].first) ++j;
    if (j - i != 2 || tail(keys[i].second) == tail(keys[i + 1].second))
      throw InvalidInput("cut mesh: edge " + std::to_string(tail(keys[i].second)) + "-" +
                         std::to_string(head(keys[i].second)) +
                         " is not shared by exactly two oppositely oriented faces");
    link(keys[i].second, keys[i + 1].second);
    i = j;
  }
  for (int v = 0; v < num_vertices(); ++v)
    if (vertex_halfedge_[v] < 0)
      throw InvalidInput("cut mesh: vertex " + std::to_string(v) + " is used by no face");
}

int CutMesh::find_halfedge(int a, int b) const {
  const int start = vertex_halfedge_[a];
  int h = start;
  do {
    if (head(h) == b) return h;
    h = rotate_ccw(h);
  } while (h != start);
  return -1;
}

// Face f = (x, y, z) with h = x->y at corner k, and its twin face g = (y, x, w):
//   f -> (x, m, z), new F1 = (m, y, z);  g -> (y, m, w), new F2 = (m, x, w).
// Half-edge 3f+k keeps meaning "x -> (m)", 3g+k' keeps "y -> (m)".
int CutMesh::split_edge(int h, double t) {
  const int ht = opp_[h];
  const int f = face_of(h), g = face_of(ht);
  const int k = h % 3, kt = ht % 3;
  const int x = tail(h), y = head(h);
  const int z = faces_[f][(k + 2) % 3], w = faces_[g][(kt + 2) % 3];
  const int o_yz = opp_[3 * f + (k + 1) % 3];   // opposite of y->z
  const int o_xw = opp_[3 * g + (kt + 1) % 3];  // opposite of x->w

  const int m = num_vertices();
  positions_.push_back((1 - t) * positions_[x] + t * positions_[y]);
  vertex_halfedge_.push_back(-1);
  const int f1 = num_faces(), f2 = f1 + 1;
  faces_.push_back({m, y, z});
  faces_.push_back({m, x, w});
  face_patch_.push_back(face_patch_[f]);
  face_patch_.push_back(face_patch_[g]);
  opp_.resize(3 * faces_.size(), -1);
  faces_[f][(k + 1) % 3] = m;
  faces_[g][(kt + 1) % 3] = m;

  const int f_xm = 3 * f + k, f_mz = 3 * f + (k + 1) % 3;
  const int g_ym = 3 * g + kt, g_mw = 3 * g + (kt + 1) % 3;
  link(3 * f1 + 1, o_yz);         // y->z
  link(f_mz, 3 * f1 + 2);         // m->z | z->m
  link(3 * f2 + 1, o_xw);         // x->w
  link(g_mw, 3 * f2 + 2);         // m->w | w->m
  link(f_xm, 3 * f2 + 0);         // x->m | m->x
  link(3 * f1 + 0, g_ym);         // m->y | y->m
  vertex_halfedge_[x] = f_xm;
  vertex_halfedge_[y] = g_ym;
  vertex_halfedge_[m] = 3 * f1;
  return m;
}

// Face f = (a, b, c) -> f = (a, b, m), F1 = (b, c, m), F2 = (c, a, m).
int CutMesh::split_face(int f, const Vec3& bary) {
  const int a = faces_[f][0], b = faces_[f][1], c = faces_[f][2];
  const int o_bc = opp_[3 * f + 1], o_ca = opp_[3 * f + 2];
  const int m = num_vertices();
  positions_.push_back(bary[0] * positions_[a] + bary[1] * positions_[b] + bary[2] * positions_[c]);
  vertex_halfedge_.push_back(-1);
  const int f1 = num_faces(), f2 = f1 + 1;
  faces_[f] = {a, b, m};
  faces_.push_back({b, c, m});
  faces_.push_back({c, a, m});
  face_patch_.push_back(face_patch_[f]);
  face_patch_.push_back(face_patch_[f]);
  opp_.resize(3 * faces_.size(), -1);
  link(3 * f1 + 0, o_bc);
  link(3 * f2 + 0, o_ca);
  link(3 * f + 1, 3 * f1 + 2);   // b->m | m->b
  link(3 * f1 + 1, 3 * f2 + 2);  // c->m | m->c
  link(3 * f2 + 1, 3 * f + 2);   // a->m | m->a
  vertex_halfedge_[a] = 3 * f;
  vertex_halfedge_[b] = 3 * f + 1;
  vertex_halfedge_[c] = 3 * f1 + 1;
  vertex_halfedge_[m] = 3 * f + 2;
  return m;
}

}  // namespace qs::dissect
