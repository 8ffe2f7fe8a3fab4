#pragma once
// The mesh that the dissection cuts: an array half-edge triangle mesh that supports edge and face
// splits, with a patch label per face. Half-edge h = 3f + k runs from faces[f][k] to
// faces[f][(k+1)%3]; its opposite is opp[h]. Every mesh here is closed and manifold.

#include <vector>

#include "qs/core/mesh.h"

namespace qs::dissect {

class CutMesh {
 public:
  /// \pre mesh is closed, manifold and consistently oriented. \throws InvalidInput otherwise.
  explicit CutMesh(const TriMesh& mesh);

  int num_vertices() const { return static_cast<int>(positions_.size()); }
  int num_faces() const { return static_cast<int>(faces_.size()); }
  const std::vector<Vec3>& positions() const { return positions_; }
  const std::vector<Tri>& faces() const { return faces_; }
  const Tri& face(int f) const { return faces_[f]; }
  const Vec3& position(int v) const { return positions_[v]; }

  static int face_of(int h) { return h / 3; }
  static int next(int h) { return h % 3 == 2 ? h - 2 : h + 1; }
  static int prev(int h) { return h % 3 == 0 ? h + 2 : h - 1; }
  int opposite(int h) const { return opp_[h]; }
  int tail(int h) const { return faces_[h / 3][h % 3]; }
  int head(int h) const { return faces_[h / 3][(h % 3 + 1) % 3]; }
  /// One half-edge leaving v.
  int out_halfedge(int v) const { return vertex_halfedge_[v]; }
  /// The next half-edge leaving the same vertex, counter-clockwise.
  int rotate_ccw(int h) const { return opp_[prev(h)]; }
  /// The half-edge a->b, or -1 if a and b are not joined by an edge.
  int find_halfedge(int a, int b) const;

  int patch(int f) const { return face_patch_[f]; }
  void set_patch(int f, int p) { face_patch_[f] = p; }
  const std::vector<int>& face_patches() const { return face_patch_; }

  /// Splits the edge of half-edge h at parameter t in (0,1) from tail to head; the 2 faces become
  /// 4 (new faces keep their patch labels). Returns the new vertex. Half-edge ids of h and of the
  /// old faces' other half-edges stay valid as documented in the .cpp.
  int split_edge(int h, double t);
  /// Splits face f at barycentric point (a, b, c) into 3 faces; returns the new vertex.
  int split_face(int f, const Vec3& bary);

  TriMesh to_trimesh() const { return {positions_, faces_}; }
  /// Makes the mesh what CutMesh(to_trimesh()) builds (the same out-half-edges, every patch label
  /// 0) without pairing its half-edges again. \pre no checkpoint() pending.
  void reset();

  /// Starts recording the splits, so that rollback() can undo them without a copy of the mesh.
  void checkpoint();
  /// Undoes every split since checkpoint() and stops recording.
  void rollback();
  /// Keeps every split since checkpoint() and stops recording.
  void commit();

 private:
  void link(int a, int b) {
    set_opp(a, b);
    set_opp(b, a);
  }
  void set_opp(int h, int value);
  void set_corner(int f, int c, int v);
  void set_vertex_halfedge(int v, int h);
  /// What checkpoint() saw, and the old values of entries that existed then, in write order.
  struct Journal {
    bool on = false;
    size_t vertices = 0, faces = 0;
    struct Entry {
      char array;  ///< 'o': opp_, 'c': a face corner (index 3f+c), 'v': vertex_halfedge_
      int index, old;
    };
    std::vector<Entry> entries;
  };
  Journal journal_;
  std::vector<Vec3> positions_;
  std::vector<Tri> faces_;
  std::vector<int> opp_;
  std::vector<int> vertex_halfedge_;
  std::vector<int> face_patch_;
};

}  // namespace qs::dissect
