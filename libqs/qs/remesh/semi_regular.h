#pragma once
// The semi-regular remesh of a set: ONE connectivity and one position array per mesh, plus
// where each vertex sits in the dissection (patch, u, v).
//
// Vertex order (uniform level n, N = 2^n; the adaptive remesh keeps the subsequence of the
// level-L uniform order it uses, L its finest level):
//   1. the base vertices (patch corners), numbered as in base_topology.h;
//   2. per base edge e, in edge order, its N-1 side-interior samples, in the edge's direction
//      (from the owner patch's corner k to corner k+1);
//   3. per patch p, in patch order, its (N-1)^2 interior samples, row by row: v = j/N outer,
//      u = i/N inner, i, j = 1..N-1.
// The (patch, u, v) recorded for a shared vertex is the one in the lowest-index patch holding it:
// for a base vertex the first (patch, corner) met walking the patches in order, for a side
// sample the edge's owner.

#include <array>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"

namespace qs::remesh {

class ChartSampler;

/// Connectivity shared by every mesh of a set (a function of the patch list and the level or the
/// adaptive quadtrees only, never of the chart geometry).
struct SemiRegularConnectivity {
  std::vector<Tri> faces;                  ///< #F triangles, counter-clockwise seen from outside
  std::vector<std::array<int, 4>> quads;   ///< uniform remesh with quads asked for: the grid cells,
                                           ///< #P * 4^n, CCW, patch by patch, row by row
  std::vector<int> vertex_patch;           ///< #V: the patch of the vertex's (patch, u, v)
  std::vector<Vec2> vertex_uv;             ///< #V: its (u, v) in that patch
  int num_base_vertices = 0;               ///< the first vertices are the base vertices
  int num_base_edges = 0;
  int num_patches = 0;
  int level = 0;                           ///< uniform: n; adaptive: the finest leaf level
  int num_vertices() const { return static_cast<int>(vertex_patch.size()); }
  int num_faces() const { return static_cast<int>(faces.size()); }
};

/// One remeshed mesh.
struct SemiRegular {
  SemiRegularConnectivity connectivity;
  std::vector<Vec3> positions;             ///< #V
  TriMesh mesh() const { return {positions, connectivity.faces}; }
};

/// A remeshed set: one connectivity, N position arrays (mesh i has positions[i]).
struct SemiRegularSet {
  SemiRegularConnectivity connectivity;
  std::vector<std::vector<Vec3>> positions;  ///< #meshes x #V
  TriMesh mesh(int i) const { return {positions.at(i), connectivity.faces}; }
};

/// The 3D position of every vertex of `connectivity` on the chart behind `sampler`
/// (ChartSampler::point at the vertex's (patch, u, v)). Checks context's cancel flag.
/// \pre connectivity was made for a patch list with the same structure as the sampler's chart.
std::vector<Vec3> sample_positions(const ChartSampler& sampler, const SemiRegularConnectivity& connectivity,
                                   const Context& context = {});

}  // namespace qs::remesh
