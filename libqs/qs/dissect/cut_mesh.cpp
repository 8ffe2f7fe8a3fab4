#include "qs/dissect/cut_mesh.h"

#include <algorithm>
#include <string>

#include "qs/core/error.h"

namespace qs::dissect {

CutMesh::CutMesh(const TriMesh& mesh) : positions_(mesh.positions), faces_(mesh.faces) {
  const int nh = 3 * num_faces();
  opp_.assign(nh, -1);
  vertex_halfedge_.assign(num_vertices(), -1);
  face_patch_.assign(num_faces(), 0);
  // Pair half-edges in the order of their (min, max, h) keys: two stable counting sorts, by the
  // larger end and then by the smaller one (linear time).
  const int nv = num_vertices();
  for (const Tri& t : faces_)
    for (int v : t)
      if (v < 0 || v >= nv)
        throw InvalidInput("cut mesh: a face refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
  std::vector<int> start(nv + 1), by_max(nh), order(nh), lo(nh), hi(nh);
  for (int h = 0; h < nh; ++h) {
    lo[h] = std::min(tail(h), head(h));
    hi[h] = std::max(tail(h), head(h));
  }
  auto counting_sort = [&](const std::vector<int>& in, std::vector<int>& out, const std::vector<int>& key) {
    std::fill(start.begin(), start.end(), 0);
    for (int h = 0; h < nh; ++h) ++start[key[h] + 1];
    for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
    for (int h : in) out[start[key[h]]++] = h;
  };
  for (int h = 0; h < nh; ++h) {
    order[h] = h;
    vertex_halfedge_[tail(h)] = h;
  }
  counting_sort(order, by_max, hi);
  counting_sort(by_max, order, lo);
  auto same_edge = [&](int a, int b) { return lo[a] == lo[b] && hi[a] == hi[b]; };
  for (int i = 0; i < nh;) {
    int j = i;
    while (j < nh && same_edge(order[j], order[i])) ++j;
    if (j - i != 2 || tail(order[i]) == tail(order[i + 1]))
      throw InvalidInput("cut mesh: edge " + std::to_string(tail(order[i])) + "-" + std::to_string(head(order[i])) +
                         " is not shared by exactly two oppositely oriented faces");
    link(order[i], order[i + 1]);
    i = j;
  }
  for (int v = 0; v < num_vertices(); ++v)
    if (vertex_halfedge_[v] < 0)
      throw InvalidInput("cut mesh: vertex " + std::to_string(v) + " is used by no face");
}

void CutMesh::reset() {
  if (journal_.on) throw InternalError("cut mesh: reset with a checkpoint pending");
  // The constructor's choice: the last half-edge leaving each vertex (the pairing is unique).
  for (int h = 0; h < 3 * num_faces(); ++h) vertex_halfedge_[tail(h)] = h;
  std::fill(face_patch_.begin(), face_patch_.end(), 0);
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
  set_corner(f, (k + 1) % 3, m);
  set_corner(g, (kt + 1) % 3, m);

  const int f_xm = 3 * f + k, f_mz = 3 * f + (k + 1) % 3;
  const int g_ym = 3 * g + kt, g_mw = 3 * g + (kt + 1) % 3;
  link(3 * f1 + 1, o_yz);         // y->z
  link(f_mz, 3 * f1 + 2);         // m->z | z->m
  link(3 * f2 + 1, o_xw);         // x->w
  link(g_mw, 3 * f2 + 2);         // m->w | w->m
  link(f_xm, 3 * f2 + 0);         // x->m | m->x
  link(3 * f1 + 0, g_ym);         // m->y | y->m
  set_vertex_halfedge(x, f_xm);
  set_vertex_halfedge(y, g_ym);
  set_vertex_halfedge(m, 3 * f1);
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
  set_corner(f, 2, m);
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
  set_vertex_halfedge(a, 3 * f);
  set_vertex_halfedge(b, 3 * f + 1);
  set_vertex_halfedge(c, 3 * f1 + 1);
  set_vertex_halfedge(m, 3 * f + 2);
  return m;
}

void CutMesh::set_opp(int h, int value) {
  if (journal_.on && static_cast<size_t>(h) < 3 * journal_.faces) journal_.entries.push_back({'o', h, opp_[h]});
  opp_[h] = value;
}

void CutMesh::set_corner(int f, int c, int v) {
  if (journal_.on && static_cast<size_t>(f) < journal_.faces) journal_.entries.push_back({'c', 3 * f + c, faces_[f][c]});
  faces_[f][c] = v;
}

void CutMesh::set_vertex_halfedge(int v, int h) {
  if (journal_.on && static_cast<size_t>(v) < journal_.vertices)
    journal_.entries.push_back({'v', v, vertex_halfedge_[v]});
  vertex_halfedge_[v] = h;
}

void CutMesh::checkpoint() {
  journal_.on = true;
  journal_.vertices = positions_.size();
  journal_.faces = faces_.size();
  journal_.entries.clear();
}

void CutMesh::rollback() {
  if (!journal_.on) throw InternalError("cut mesh: rollback without a checkpoint");
  for (auto e = journal_.entries.rbegin(); e != journal_.entries.rend(); ++e) {
    if (e->array == 'o') opp_[e->index] = e->old;
    else if (e->array == 'c') faces_[e->index / 3][e->index % 3] = e->old;
    else vertex_halfedge_[e->index] = e->old;
  }
  positions_.resize(journal_.vertices);
  vertex_halfedge_.resize(journal_.vertices);
  faces_.resize(journal_.faces);
  face_patch_.resize(journal_.faces);
  opp_.resize(3 * journal_.faces);
  commit();
}

void CutMesh::commit() {
  journal_.on = false;
  journal_.entries.clear();
}

}  // namespace qs::dissect
