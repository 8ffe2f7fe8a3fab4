#include "qs/mesh/connectivity.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

namespace qs::mesh {
namespace {

using qs::test::tetrahedron;

/// Every face as its three rotations, to look up "is (a, b, c) a face, in this orientation".
std::set<std::array<int, 3>> oriented_faces(const TriMesh& m) {
  std::set<std::array<int, 3>> s;
  for (const Tri& t : m.faces) {
    s.insert({t[0], t[1], t[2]});
    s.insert({t[1], t[2], t[0]});
    s.insert({t[2], t[0], t[1]});
  }
  return s;
}

void expect_throws_with(const TriMesh& m, const std::string& part) {
  try {
    build_connectivity(m);
    ADD_FAILURE() << "expected InvalidInput containing '" << part << "'";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(Connectivity, HalfedgeArithmetic) {
  for (int f = 0; f < 5; ++f)
    for (int k = 0; k < 3; ++k) {
      const int h = 3 * f + k;
      EXPECT_EQ(Connectivity::face(h), f);
      EXPECT_EQ(Connectivity::next(h), 3 * f + (k + 1) % 3);
      EXPECT_EQ(Connectivity::prev(h), 3 * f + (k + 2) % 3);
      EXPECT_EQ(Connectivity::prev(Connectivity::next(h)), h);
    }
  EXPECT_EQ(Connectivity::face_halfedge(4), 12);
}

TEST(Connectivity, OppositeIsAnInvolutionOnAClosedMesh) {
  const TriMesh m = shapes::icosphere(3);
  const Connectivity c = build_connectivity(m);
  ASSERT_EQ(c.num_halfedges(), 3 * m.num_faces());
  ASSERT_EQ(c.num_vertices(), m.num_vertices());
  for (int h = 0; h < c.num_halfedges(); ++h) {
    const int o = c.opposite[h];
    ASSERT_GE(o, 0);
    EXPECT_NE(o, h);
    EXPECT_NE(Connectivity::face(o), Connectivity::face(h));
    EXPECT_EQ(c.opposite[o], h);
    EXPECT_EQ(c.tail(o), c.head(h));
    EXPECT_EQ(c.head(o), c.tail(h));
    EXPECT_EQ(c.tail(h), m.faces[h / 3][h % 3]);
  }
}

TEST(Connectivity, OneRingIsCounterClockwiseAndComplete) {
  const TriMesh m = shapes::icosphere(2);
  const Connectivity c = build_connectivity(m);
  const auto faces = oriented_faces(m);
  long long valence_sum = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    EXPECT_FALSE(c.is_boundary_vertex(v));
    EXPECT_EQ(c.tail(c.vertex_halfedge[v]), v);
    const std::vector<int> ring = c.one_ring(v);
    EXPECT_EQ(static_cast<int>(ring.size()), c.valence(v));
    EXPECT_TRUE(ring.size() == 5 || ring.size() == 6) << v;
    for (std::size_t i = 0; i < ring.size(); ++i)
      EXPECT_TRUE(faces.count({v, ring[i], ring[(i + 1) % ring.size()]})) << "vertex " << v;
    valence_sum += c.valence(v);
  }
  EXPECT_EQ(valence_sum, 3LL * m.num_faces());  // = 2E
}

TEST(Connectivity, OpenDiskBoundary) {
  const int rings = 3;
  const TriMesh m = shapes::open_disk(rings);
  const Connectivity c = build_connectivity(m);
  const auto faces = oriented_faces(m);
  const int boundary_halfedges =
      static_cast<int>(std::count(c.opposite.begin(), c.opposite.end(), -1));
  EXPECT_EQ(boundary_halfedges, 6 * rings);
  int boundary_vertices = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    if (!c.is_boundary_vertex(v)) {
      EXPECT_EQ(c.valence(v), 6);
      continue;
    }
    ++boundary_vertices;
    EXPECT_TRUE(c.is_boundary_halfedge(c.vertex_halfedge[v]));
    const std::vector<int> ring = c.one_ring(v);
    // A boundary fan: consecutive neighbours form faces, but the last and the first do not.
    for (std::size_t i = 0; i + 1 < ring.size(); ++i)
      EXPECT_TRUE(faces.count({v, ring[i], ring[i + 1]}));
    EXPECT_FALSE(faces.count({v, ring.back(), ring.front()}));
    int outgoing = 0;
    c.for_each_outgoing(v, [&](int h) {
      EXPECT_EQ(c.tail(h), v);
      ++outgoing;
    });
    EXPECT_EQ(outgoing + 1, static_cast<int>(ring.size()));
  }
  EXPECT_EQ(boundary_vertices, 6 * rings);
}

TEST(Connectivity, IsolatedVertexHasNoHalfedge) {
  TriMesh m = tetrahedron();
  m.positions.emplace_back(5, 5, 5);
  const Connectivity c = build_connectivity(m);
  EXPECT_EQ(c.vertex_halfedge[4], -1);
  EXPECT_TRUE(c.one_ring(4).empty());
  EXPECT_EQ(c.valence(4), 0);
}

TEST(Connectivity, GroupHalfedgesSortsEdges) {
  const TriMesh m = shapes::cube_sphere(3);
  const EdgeGroups g = group_halfedges(m.faces, m.num_vertices());
  EXPECT_EQ(g.num_edges(), 3 * m.num_faces() / 2);
  ASSERT_EQ(static_cast<int>(g.offsets.size()), g.num_edges() + 1);
  std::vector<int> seen(3 * m.num_faces(), 0);
  for (int e = 0; e < g.num_edges(); ++e) {
    EXPECT_EQ(g.size(e), 2);
    EXPECT_LT(g.vertices[e][0], g.vertices[e][1]);
    if (e > 0) {
      EXPECT_LT(g.vertices[e - 1], g.vertices[e]);
    }
    for (int i = g.offsets[e]; i < g.offsets[e + 1]; ++i) {
      const int h = g.halfedges[i];
      ++seen[h];
      const int a = m.faces[h / 3][h % 3], b = m.faces[h / 3][(h % 3 + 1) % 3];
      EXPECT_EQ(std::min(a, b), g.vertices[e][0]);
      EXPECT_EQ(std::max(a, b), g.vertices[e][1]);
    }
  }
  EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
}

TEST(Connectivity, NonManifoldEdgeThrowsNamingTheEdge) {
  expect_throws_with(shapes::nonmanifold_fan(), "non-manifold edge 0-1 has 3 faces");
}

TEST(Connectivity, SameDirectionEdgeThrows) {
  TriMesh m = tetrahedron();
  std::swap(m.faces[3][1], m.faces[3][2]);
  expect_throws_with(m, "same direction");
}

TEST(Connectivity, BowtieVertexThrows) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  m.faces = {{0, 1, 2}, {0, 3, 4}};
  expect_throws_with(m, "vertex 0 is non-manifold");
}

TEST(Connectivity, BadFacesThrow) {
  TriMesh m = tetrahedron();
  m.faces.push_back({0, 1, 9});
  expect_throws_with(m, "face 4 has vertex index 9 outside [0, 4)");
  m.faces.back() = {2, 2, 1};
  expect_throws_with(m, "face 4 uses a vertex twice");
}

}  // namespace
}  // namespace qs::mesh
