#include "qs/mesh/validate.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

namespace qs::mesh {
namespace {

using qs::test::tetrahedron;

using Ids = std::vector<long long>;

/// Appends b to a, shifting b's vertex ids.
void append(TriMesh& a, const TriMesh& b) {
  const int off = a.num_vertices();
  for (const Vec3& p : b.positions) a.positions.push_back(p);
  for (const Tri& t : b.faces) a.faces.push_back({t[0] + off, t[1] + off, t[2] + off});
}

/// Signed volume computed here, independently of the library (about the origin).
double volume_of(const TriMesh& m) {
  double v = 0;
  for (const Tri& t : m.faces)
    v += m.positions[t[0]].dot(m.positions[t[1]].cross(m.positions[t[2]])) / 6.0;
  return v;
}

std::vector<std::string> kinds(const ValidationReport& r) {
  std::vector<std::string> k;
  for (const Problem& p : r.problems) k.push_back(p.kind);
  return k;
}

const Problem& problem(const ValidationReport& r, const char* kind) {
  const Problem* p = find_problem(r, kind);
  if (!p) {
    ADD_FAILURE() << "no problem '" << kind << "' in:\n" << format_report("mesh", r);
    static const Problem none;
    return none;
  }
  return *p;
}

TEST(Validate, TetrahedronIsAccepted) {
  const ValidationResult res = validate(tetrahedron());
  const ValidationReport& r = res.report;
  EXPECT_TRUE(r.accepted) << format_report("tet", r);
  EXPECT_TRUE(r.problems.empty());
  EXPECT_EQ(r.vertices, 4);
  EXPECT_EQ(r.faces, 4);
  EXPECT_EQ(r.edges, 6);
  EXPECT_EQ(r.euler_characteristic, 2);
  EXPECT_EQ(r.genus, 0);
  EXPECT_EQ(r.components, 1);
  EXPECT_TRUE(r.boundary_loop_sizes.empty());
  EXPECT_FALSE(r.orientation_flipped);
  EXPECT_NEAR(r.min_angle_degrees, 60.0, 1e-9);
  EXPECT_NEAR(r.bbox_diagonal, std::sqrt(12.0), 1e-12);
  EXPECT_NEAR(r.signed_volume, volume_of(tetrahedron()), 1e-12);
  EXPECT_GT(r.signed_volume, 0);
  EXPECT_EQ(res.mesh.faces, tetrahedron().faces);
  EXPECT_EQ(res.vertex_map, (std::vector<int>{0, 1, 2, 3}));
}

TEST(Validate, EmptyMeshIsRejected) {
  for (const TriMesh& m : {TriMesh{}, TriMesh{tetrahedron().positions, {}}}) {
    const ValidationReport r = validate(m).report;
    EXPECT_FALSE(r.accepted);
    EXPECT_EQ(kinds(r).front(), "empty");
    EXPECT_EQ(problem(r, "empty").severity, Severity::Fatal);
    EXPECT_EQ(problem(r, "empty").count, 1);
    EXPECT_EQ(r.vertices, 0);
    EXPECT_NE(format_report("e", r).find("rejected: empty"), std::string::npos);
  }
}

TEST(Validate, InvalidVertexIndexFacesAreReportedAndDropped) {
  TriMesh m = tetrahedron();
  m.faces.push_back({0, 1, 7});
  m.faces.push_back({-1, 2, 3});
  m.faces.push_back({INT_MAX, INT_MIN, 2});
  const ValidationResult res = validate(m);
  const Problem& p = problem(res.report, "invalid_vertex_index");
  EXPECT_EQ(p.severity, Severity::Fatal);
  EXPECT_EQ(p.count, 3);
  EXPECT_EQ(p.first_ids, (Ids{4, 5, 6}));
  EXPECT_NE(p.message.find("[0, 4)"), std::string::npos) << p.message;
  EXPECT_FALSE(res.report.accepted);
  // The rest is checked as if those faces were not there: a clean tetrahedron.
  EXPECT_EQ(kinds(res.report), (std::vector<std::string>{"invalid_vertex_index"}));
  EXPECT_EQ(res.mesh.num_faces(), 4);
  EXPECT_EQ(res.report.input_faces, 7);
}

TEST(Validate, AllFacesInvalidIsEmpty) {
  TriMesh m = tetrahedron();
  for (Tri& t : m.faces) t[0] = 99;
  const ValidationReport r = validate(m).report;
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(problem(r, "invalid_vertex_index").count, 4);
  EXPECT_NE(find_problem(r, "empty"), nullptr);
  EXPECT_EQ(r.vertices, 0);
}

TEST(Validate, NonFiniteCoordinatesAreFatal) {
  TriMesh m = tetrahedron();
  m.positions[2].y() = std::numeric_limits<double>::quiet_NaN();
  m.positions[3].x() = -std::numeric_limits<double>::infinity();
  const ValidationReport r = validate(m).report;
  const Problem& p = problem(r, "non_finite_coordinates");
  EXPECT_EQ(p.count, 2);
  EXPECT_EQ(p.first_ids, (Ids{2, 3}));
  EXPECT_FALSE(r.accepted);
  EXPECT_TRUE(std::isfinite(r.bbox_diagonal));
  EXPECT_TRUE(std::isfinite(r.min_angle_degrees));
  EXPECT_FALSE(r.orientation_flipped);
}

TEST(Validate, CoordinatesTooLargeToSquareAreFatalAndTheBoxStaysFinite) {
  // 1e154 squared overflows; 1e100 is the documented limit (qs/core/finite.h).
  TriMesh m = tetrahedron();
  for (Vec3& p : m.positions) p *= 1e154;
  const ValidationReport r = validate(m).report;
  EXPECT_EQ(problem(r, "non_finite_coordinates").count, 4);
  EXPECT_FALSE(r.accepted);
  EXPECT_TRUE(std::isfinite(r.bbox_diagonal));
  TriMesh one = tetrahedron();
  one.positions[1].z() = -1e200;
  EXPECT_EQ(problem(validate(one).report, "non_finite_coordinates").first_ids, (Ids{1}));
  TriMesh edge = tetrahedron();
  for (Vec3& p : edge.positions) p *= 1e99;  // large but within the limit: accepted
  const ValidationReport ok = validate(edge).report;
  EXPECT_TRUE(ok.accepted);
  EXPECT_TRUE(std::isfinite(ok.bbox_diagonal) && std::isfinite(ok.signed_volume));
}

TEST(Validate, NonFiniteUnreferencedVertexIsOnlyDropped) {
  TriMesh m = tetrahedron();
  m.positions.emplace_back(std::nan(""), 0, 0);
  const ValidationResult res = validate(m);
  EXPECT_TRUE(res.report.accepted) << format_report("m", res.report);
  EXPECT_EQ(problem(res.report, "unreferenced_vertices").first_ids, (Ids{4}));
  EXPECT_EQ(res.mesh.num_vertices(), 4);
}

TEST(Validate, RepeatedIndexFacesAreFatal) {
  TriMesh m = tetrahedron();
  m.faces.push_back({1, 1, 2});
  m.faces.push_back({3, 0, 3});
  const ValidationResult res = validate(m);
  const Problem& p = problem(res.report, "repeated_index_faces");
  EXPECT_EQ(p.count, 2);
  EXPECT_EQ(p.first_ids, (Ids{4, 5}));
  // Skipped by the other checks (no spurious edge problems), but kept in the output.
  EXPECT_EQ(kinds(res.report), (std::vector<std::string>{"repeated_index_faces"}));
  EXPECT_EQ(res.mesh.num_faces(), 6);
  EXPECT_FALSE(res.report.accepted);
}

TEST(Validate, DuplicateFacesInAnyOrderOrOrientation) {
  TriMesh m = tetrahedron();
  m.faces.push_back({0, 1, 2});  // same
  m.faces.push_back({1, 0, 3});  // face 1 reversed
  m.faces.push_back({3, 0, 2});  // face 2 rotated
  m.faces.push_back({2, 1, 0});  // face 0 reversed, a second copy
  const ValidationResult res = validate(m);
  const Problem& p = problem(res.report, "duplicate_faces");
  EXPECT_EQ(p.severity, Severity::Fatal);
  EXPECT_EQ(p.count, 4);
  EXPECT_EQ(p.first_ids, (Ids{4, 5, 6, 7}));
  EXPECT_NE(p.message.find("4 (copy of 0)"), std::string::npos) << p.message;
  EXPECT_NE(p.message.find("7 (copy of 0)"), std::string::npos) << p.message;
  EXPECT_NE(p.message.find("5 (copy of 1)"), std::string::npos) << p.message;
  // The copies do not also show up as non-manifold edges.
  EXPECT_EQ(kinds(res.report), (std::vector<std::string>{"duplicate_faces"}));
  EXPECT_EQ(res.report.edges, 6);
}

TEST(Validate, NonManifoldEdgeOfThreePages) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {-1, 1, 0}, {-1, -1, 0}};
  m.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const ValidationReport r = validate(m).report;
  const Problem& p = problem(r, "non_manifold_edges");
  EXPECT_EQ(p.count, 1);
  EXPECT_EQ(p.first_ids, (Ids{0, 1}));
  EXPECT_EQ(p.message, "non-manifold edges: 1 (first: 0-1); each edge must have exactly two faces");
  EXPECT_EQ(problem(r, "boundary_edges").count, 6);
  EXPECT_EQ(find_problem(r, "non_manifold_vertices"), nullptr);  // one fan around the edge
  EXPECT_EQ(r.genus, -1);
  EXPECT_FALSE(r.accepted);
}

TEST(Validate, TwoTetrahedraSharingAnEdge) {
  // A second, consistently oriented tetrahedron on vertices 0, 1, 4, 5.
  TriMesh m = tetrahedron();
  m.positions.push_back({3, 3, 1});
  m.positions.push_back({3, 1, -1});
  m.faces.push_back({0, 1, 4});
  m.faces.push_back({1, 5, 4});
  m.faces.push_back({1, 0, 5});
  m.faces.push_back({0, 4, 5});
  const ValidationReport r = validate(m).report;
  const Problem& p = problem(r, "non_manifold_edges");
  EXPECT_EQ(p.count, 1);
  EXPECT_EQ(p.first_ids, (Ids{0, 1}));
  EXPECT_EQ(find_problem(r, "boundary_edges"), nullptr);
  EXPECT_EQ(find_problem(r, "non_manifold_vertices"), nullptr);
  EXPECT_EQ(r.genus, -1);
}

TEST(Validate, BowtieVertexOfTwoClosedTetrahedra) {
  TriMesh m = tetrahedron();
  append(m, tetrahedron(Vec3(0, 0, 4)));
  // Merge b's vertex 0 (id 4) into vertex 0.
  for (std::size_t f = 4; f < m.faces.size(); ++f)
    for (int& v : m.faces[f])
      if (v == 4) v = 0;
  const ValidationResult res = validate(m);
  const ValidationReport& r = res.report;
  const Problem& p = problem(r, "non_manifold_vertices");
  EXPECT_EQ(p.count, 1);
  EXPECT_EQ(p.first_ids, (Ids{0}));
  EXPECT_EQ(r.components, 1);  // connected through the shared vertex
  EXPECT_EQ(kinds(r), (std::vector<std::string>{"non_manifold_vertices", "unreferenced_vertices"}));
  EXPECT_EQ(r.genus, -1);
  EXPECT_FALSE(r.accepted);
}

TEST(Validate, OpenBowtieOfTwoTriangles) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  m.faces = {{0, 1, 2}, {0, 3, 4}};
  const ValidationReport r = validate(m).report;
  EXPECT_EQ(problem(r, "non_manifold_vertices").first_ids, (Ids{0}));
  EXPECT_EQ(problem(r, "boundary_edges").count, 6);
  std::vector<int> loops = r.boundary_loop_sizes;
  std::sort(loops.begin(), loops.end());
  EXPECT_EQ(loops, (std::vector<int>{3, 3}));
}

TEST(Validate, OpenTetrahedronHasOneBoundaryLoop) {
  TriMesh m = tetrahedron();
  m.faces.erase(m.faces.begin() + 3);  // (1, 3, 2)
  const ValidationReport r = validate(m).report;
  const Problem& p = problem(r, "boundary_edges");
  EXPECT_EQ(p.count, 3);
  EXPECT_EQ(p.first_ids, (Ids{1, 2, 1, 3, 2, 3}));
  EXPECT_EQ(r.boundary_loop_sizes, (std::vector<int>{3}));
  EXPECT_EQ(kinds(r), (std::vector<std::string>{"boundary_edges"}));
  EXPECT_EQ(r.genus, -1);
  EXPECT_EQ(r.signed_volume, 0);
}

TEST(Validate, FirstIdsAreCappedAtTen) {
  const ValidationReport r = validate(shapes::open_disk(3)).report;
  const Problem& p = problem(r, "boundary_edges");
  EXPECT_EQ(p.count, 18);
  EXPECT_EQ(p.first_ids.size(), 20u);  // 10 vertex pairs
  EXPECT_NE(p.message.find(", ...)"), std::string::npos) << p.message;
  for (std::size_t i = 0; i < p.first_ids.size(); i += 2)
    EXPECT_LT(p.first_ids[i], p.first_ids[i + 1]);
}

TEST(Validate, FlippedFaceIsInconsistentOrientation) {
  TriMesh m = tetrahedron();
  std::swap(m.faces[0][1], m.faces[0][2]);  // (0, 2, 1)
  const ValidationReport r = validate(m).report;
  const Problem& p = problem(r, "inconsistent_orientation");
  EXPECT_EQ(p.count, 3);
  EXPECT_EQ(p.first_ids, (Ids{0, 1, 0, 2, 1, 2}));
  EXPECT_EQ(kinds(r), (std::vector<std::string>{"inconsistent_orientation"}));
  EXPECT_FALSE(r.orientation_flipped);
  EXPECT_EQ(r.genus, -1);
  EXPECT_FALSE(r.accepted);
}

TEST(Validate, TwoComponents) {
  TriMesh m = tetrahedron();
  append(m, tetrahedron(Vec3(5, 0, 0)));
  const ValidationReport r = validate(m).report;
  const Problem& p = problem(r, "multiple_components");
  EXPECT_EQ(p.count, 2);
  EXPECT_EQ(p.first_ids, (Ids{0, 4}));
  EXPECT_EQ(r.components, 2);
  EXPECT_EQ(r.genus, -1);
  EXPECT_EQ(r.euler_characteristic, 4);
  EXPECT_EQ(kinds(r), (std::vector<std::string>{"multiple_components"}));
  EXPECT_FALSE(r.accepted);
}

TEST(Validate, TorusIsGenusOne) {
  const ValidationReport r = validate(shapes::torus(12, 8)).report;
  const Problem& p = problem(r, "genus");
  EXPECT_EQ(p.count, 1);
  EXPECT_EQ(p.message, "mesh is genus 1 (V-E+F = 0); qs needs closed genus-0 meshes");
  EXPECT_EQ(r.genus, 1);
  EXPECT_EQ(r.euler_characteristic, 0);
  EXPECT_FALSE(r.orientation_flipped);  // the torus is built outward
  EXPECT_GT(r.signed_volume, 0);
  EXPECT_FALSE(r.accepted);
}

TEST(Validate, ComponentWithGenusAmongSeveral) {
  TriMesh m = shapes::torus(8, 6);
  append(m, tetrahedron(Vec3(5, 0, 0)));
  const ValidationReport r = validate(m).report;
  EXPECT_EQ(problem(r, "genus").count, 1);
  EXPECT_NE(problem(r, "genus").message.find("1 of 2 components"), std::string::npos);
  EXPECT_EQ(problem(r, "multiple_components").count, 2);
}

TEST(Validate, InsideOutIcosphereIsFlippedAndAccepted) {
  TriMesh m = shapes::icosphere(2);
  for (Tri& t : m.faces) std::swap(t[0], t[1]);
  ASSERT_LT(volume_of(m), 0);
  const ValidationResult res = validate(m);
  const ValidationReport& r = res.report;
  EXPECT_TRUE(r.accepted) << format_report("inside-out", r);
  const Problem& p = problem(r, "orientation_flipped");
  EXPECT_EQ(p.severity, Severity::Note);
  EXPECT_EQ(p.count, m.num_faces());
  EXPECT_TRUE(r.orientation_flipped);
  EXPECT_GT(volume_of(res.mesh), 0);
  EXPECT_NEAR(r.signed_volume, volume_of(res.mesh), 1e-9);
  ASSERT_EQ(res.mesh.num_faces(), m.num_faces());
  for (int f = 0; f < m.num_faces(); ++f) {
    const Tri& a = m.faces[f];
    EXPECT_EQ(res.mesh.faces[f], (Tri{a[0], a[2], a[1]}));  // corners 1 and 2 swapped
  }
}

TEST(Validate, UnreferencedVerticesAreDroppedAndRenumbered) {
  const TriMesh tet = tetrahedron();
  TriMesh m;
  // Input vertices: 0 unused, 1 = tet 0, 2 = tet 1, 3 unused, 4 = tet 2, 5 = tet 3, 6 unused.
  m.positions = {Vec3(9, 9, 9),    tet.positions[0], tet.positions[1], Vec3(8, 8, 8),
                 tet.positions[2], tet.positions[3], Vec3(7, 7, 7)};
  const int to_input[4] = {1, 2, 4, 5};
  for (const Tri& t : tet.faces)
    m.faces.push_back({to_input[t[0]], to_input[t[1]], to_input[t[2]]});
  const ValidationResult res = validate(m);
  EXPECT_TRUE(res.report.accepted) << format_report("m", res.report);
  const Problem& p = problem(res.report, "unreferenced_vertices");
  EXPECT_EQ(p.severity, Severity::Note);
  EXPECT_EQ(p.count, 3);
  EXPECT_EQ(p.first_ids, (Ids{0, 3, 6}));
  EXPECT_EQ(res.vertex_map, (std::vector<int>{-1, 0, 1, -1, 2, 3, -1}));
  EXPECT_EQ(res.mesh.positions, tet.positions);
  EXPECT_EQ(res.mesh.faces, tet.faces);
  EXPECT_EQ(res.report.input_vertices, 7);
  EXPECT_EQ(res.report.vertices, 4);
  // Ids in problems refer to the input: a face flipped in the input names input vertices.
  std::swap(m.faces[0][1], m.faces[0][2]);
  const ValidationReport flipped = validate(m).report;
  EXPECT_EQ(problem(flipped, "inconsistent_orientation").first_ids, (Ids{1, 2, 1, 4, 2, 4}));
}

/// A closed bipyramid over the triangle (a, b, c); `top` may be put almost in line with a and b.
TriMesh bipyramid(const Vec3& top) {
  TriMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, top, {0.3, 0.3, -1}};
  m.faces = {{0, 1, 3}, {1, 2, 3}, {2, 0, 3}, {1, 0, 4}, {2, 1, 4}, {0, 2, 4}};
  return m;
}

TEST(Validate, ZeroAreaFaceIsAWarning) {
  const ValidationResult res = validate(bipyramid(Vec3(2, 0, 0)));
  const ValidationReport& r = res.report;
  EXPECT_TRUE(r.accepted) << format_report("m", r);
  const Problem& p = problem(r, "zero_area_faces");
  EXPECT_EQ(p.severity, Severity::Warning);
  EXPECT_EQ(p.count, 1);
  EXPECT_EQ(p.first_ids, (Ids{0}));
  EXPECT_EQ(find_problem(r, "tiny_angles"), nullptr);  // zero-area faces are not measured
  EXPECT_GT(r.min_angle_degrees, 1.0);
}

TEST(Validate, TinyAngleIsAWarning) {
  const Vec3 top(2, 0, 1e-3);
  const ValidationReport r = validate(bipyramid(top)).report;
  EXPECT_TRUE(r.accepted) << format_report("m", r);
  const Problem& p = problem(r, "tiny_angles");
  EXPECT_EQ(p.severity, Severity::Warning);
  EXPECT_EQ(p.count, 1);
  EXPECT_EQ(p.first_ids, (Ids{0}));
  // Face 0 = (0,0,0) (1,0,0) (2,0,1e-3) has the smallest angle of the mesh.
  const Vec3 p0(0, 0, 0), p1(1, 0, 0);
  auto angle = [](const Vec3& at, const Vec3& u, const Vec3& v) {
    return std::acos((u - at).normalized().dot((v - at).normalized())) * 180.0 / std::numbers::pi;
  };
  const double expected = std::min({angle(p0, p1, top), angle(p1, top, p0), angle(top, p0, p1)});
  EXPECT_LT(expected, 0.03);
  EXPECT_NEAR(r.min_angle_degrees, expected, 1e-6);
  EXPECT_EQ(find_problem(r, "zero_area_faces"), nullptr);
  // The threshold is an option.
  ValidateOptions o;
  o.tiny_angle_degrees = 0.01;
  EXPECT_EQ(find_problem(validate(bipyramid(top), o).report, "tiny_angles"), nullptr);
}

TEST(Validate, EveryProblemAtOnce) {
  TriMesh m = tetrahedron();
  append(m, tetrahedron(Vec3(5, 0, 0)));  // second component
  m.faces.erase(m.faces.begin() + 7);     // opened
  m.faces.push_back({0, 1, 2});           // duplicate
  m.faces.push_back({0, 0, 2});           // repeated index
  m.faces.push_back({0, 1, 42});          // invalid index
  m.positions.emplace_back(0, 0, 0);      // unreferenced
  m.positions[3].z() = std::numeric_limits<double>::infinity();
  const ValidationReport r = validate(m).report;
  EXPECT_EQ(kinds(r),
            (std::vector<std::string>{"invalid_vertex_index", "non_finite_coordinates",
                                      "repeated_index_faces", "duplicate_faces", "boundary_edges",
                                      "multiple_components", "unreferenced_vertices"}));
  const std::string text = format_report("soup.obj", r);
  EXPECT_NE(
      text.find("rejected: invalid_vertex_index, non_finite_coordinates, repeated_index_faces, "
                "duplicate_faces, boundary_edges, multiple_components"),
      std::string::npos)
      << text;
}

TEST(Validate, GarbageNeverCrashes) {
  std::uint64_t state = 12345;
  auto rnd = [&](int n) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<int>((state >> 33) % static_cast<std::uint64_t>(n));
  };
  for (int trial = 0; trial < 200; ++trial) {
    TriMesh m;
    const int nv = rnd(12), nf = rnd(20);
    for (int v = 0; v < nv; ++v)
      m.positions.emplace_back(rnd(3), rnd(3), rnd(7) == 0 ? NAN : rnd(3));
    for (int f = 0; f < nf; ++f)
      m.faces.push_back({rnd(nv + 4) - 2, rnd(nv + 4) - 2, rnd(nv + 4) - 2});
    const ValidationResult res = validate(m);
    for (const Tri& t : res.mesh.faces)
      for (int v : t) ASSERT_TRUE(v >= 0 && v < res.mesh.num_vertices());
    for (const Problem& p : res.report.problems) {
      EXPECT_GT(p.count, 0) << p.kind;
      EXPECT_FALSE(p.message.empty());
    }
    EXPECT_FALSE(format_report("garbage", res.report).empty());
  }
}

TEST(Validate, FormatReportHasCountsAndVerdict) {
  const ValidationReport ok = validate(shapes::icosphere(1)).report;
  const std::string a = format_report("ico.off", ok);
  EXPECT_EQ(a.rfind("ico.off: 42 vertices, 80 faces, 120 edges", 0), 0u) << a;
  EXPECT_NE(a.find("genus: 0 (V-E+F = 2)"), std::string::npos) << a;
  EXPECT_NE(a.find("boundary loops: none"), std::string::npos) << a;
  EXPECT_EQ(a.substr(a.size() - 9), "accepted\n") << a;

  const ValidationReport bad = validate(shapes::open_disk(2)).report;
  const std::string b = format_report("disk.off", bad);
  EXPECT_NE(b.find("boundary loops: 1 (edges: 12)"), std::string::npos) << b;
  EXPECT_NE(b.find("error [boundary_edges]: boundary edges: 12 in 1 loop of 12 edges"),
            std::string::npos)
      << b;
  EXPECT_NE(b.find("\nrejected: boundary_edges\n"), std::string::npos) << b;
}

TEST(Validate, SignedVolumeOfAUnitCube) {
  TriMesh cube;
  for (int i = 0; i < 8; ++i) cube.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  cube.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  EXPECT_NEAR(signed_volume(cube), 1.0, 1e-12);
  const ValidationReport r = validate(cube).report;
  EXPECT_TRUE(r.accepted) << format_report("cube", r);
  EXPECT_NEAR(r.signed_volume, 1.0, 1e-12);
  EXPECT_NEAR(r.min_angle_degrees, 45.0, 1e-9);
}

}  // namespace
}  // namespace qs::mesh
