// Ground truth between meshes (sphere maps, identical connectivity, surface maps) and the measure
// of a dissection's correspondence against it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "qs/core/error.h"
#include "qs/correspondence/correspondence.h"
#include "qs/dissect/dissection.h"
#include "qs/family/family.h"
#include "qs/family/retessellate.h"
#include "qs/family/surface_map.h"
#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/validate.h"
#include "qs/shapes/shapes.h"

using ::testing::HasSubstr;
using qs::Vec3;
namespace cr = qs::correspondence;
namespace fs = std::filesystem;

namespace {

qs::family::Family small_family(int n, std::uint64_t seed, double variation = 1.0) {
  qs::family::FamilyOptions o;
  o.shapes = n;
  o.seed = seed;
  o.faces = 2000;
  o.limbs = 4;
  o.variation = variation;
  return qs::family::generate_family(o);
}

cr::TruthMesh sphere_truth(const qs::family::FamilyShape& s) {
  cr::TruthMesh t;
  t.name = s.name;
  t.mesh = s.mesh;
  qs::family::SurfaceMap m;
  m.sphere = s.parameters;
  t.map = m;
  return t;
}

cr::TruthMesh plain_truth(const qs::TriMesh& mesh, const std::string& name) {
  cr::TruthMesh t;
  t.name = name;
  t.mesh = mesh;
  return t;
}

// The shapes dissected as qs-dissect does it (seeds inserted at their surface points).
qs::dissect::DissectionSet dissect_shapes(const std::vector<const qs::family::FamilyShape*>& shapes) {
  std::vector<qs::dissect::MeshToDissect> in;
  for (const auto* s : shapes) in.push_back(cr::dissect_input(*s));
  return qs::dissect::dissect_set(in);
}

// One generated shape dissected with itself, and the identity as its truth.
struct SelfPair {
  qs::family::Family fam = small_family(1, 4);
  qs::dissect::DissectionSet set = dissect_shapes({&fam.shapes[0], &fam.shapes[0]});
  cr::GroundTruth truth{{plain_truth(fam.shapes[0].mesh, "a"), plain_truth(fam.shapes[0].mesh, "b")}};
};

std::vector<cr::DissectedInput> inputs_of(const qs::dissect::DissectionSet& set) {
  std::vector<cr::DissectedInput> in;
  for (const auto& d : set.meshes) in.push_back({&d.chart, cr::dissection_landmarks(d)});
  return in;
}

}  // namespace

TEST(GroundTruth, SphereMapsTakeLandmarksToLandmarksAndRoundTrip) {
  const auto fam = small_family(2, 3);
  const cr::GroundTruth truth({sphere_truth(fam.shapes[0]), sphere_truth(fam.shapes[1])});
  EXPECT_EQ(truth.tolerance(), 0);
  const auto &a = fam.shapes[0], &b = fam.shapes[1];
  for (std::size_t k = 0; k < a.features.size(); ++k) {
    const auto img = truth.map(0, 1, a.features[k].where);
    EXPECT_LT((qs::landmarks::position_of(b.mesh, img) - qs::landmarks::position_of(b.mesh, b.features[k].where)).norm(), 1e-9)
        << a.features[k].name;
  }
  for (int f = 0; f < a.mesh.num_faces(); f += 97) {
    qs::landmarks::SurfacePoint p;
    p.face = f;
    p.bary = {0.2, 0.3, 0.5};
    const auto there = truth.map(0, 1, p);
    for (double w : there.bary) EXPECT_GE(w, 0);
    // The image lies on B's mesh near B's smooth surface at the same parameter (within the chord
    // error of a 2000-face mesh, largest at the limb tips).
    const qs::Tri& t = a.mesh.faces[f];
    const Vec3 d = (0.2 * a.parameters[t[0]] + 0.3 * a.parameters[t[1]] + 0.5 * a.parameters[t[2]]).normalized();
    EXPECT_LT((qs::landmarks::position_of(b.mesh, there) - qs::family::family_surface_point(fam.options, 1, d)).norm(),
              0.03 * qs::bounding_box(b.mesh.positions).diagonal());
    const auto back = truth.map(1, 0, there);
    EXPECT_LT((qs::landmarks::position_of(a.mesh, back) - qs::landmarks::position_of(a.mesh, p)).norm(), 1e-9);
  }
}

TEST(GroundTruth, IdenticalConnectivityIsTheSameFaceAndWeights) {
  const qs::TriMesh m = qs::shapes::icosphere(2);
  qs::TriMesh big = m;
  for (auto& p : big.positions) p *= 3;
  const cr::GroundTruth truth({plain_truth(m, "a"), plain_truth(big, "b")});
  qs::landmarks::SurfacePoint p;
  p.face = 17;
  p.bary = {0.1, 0.6, 0.3};
  const auto q = truth.map(0, 1, p);
  EXPECT_EQ(q.face, 17);
  EXPECT_EQ(q.bary, p.bary);
}

TEST(GroundTruth, SurfaceMapsGoThroughTheirReference) {
  // B is a re-tessellation of R, which has A's connectivity: a point of A maps to R's same
  // (face, bary), then to B's closest point.
  const qs::TriMesh a = qs::mesh::validate(qs::shapes::bumpy_sphere(0.2, 3, 3)).mesh;
  qs::TriMesh r = a;
  for (auto& p : r.positions) p = qs::Vec3(1.5 * p.x(), p.y(), 0.8 * p.z());
  qs::family::RetessellateOptions ro;
  ro.faces = 1500;
  const auto re = qs::family::retessellate(r, ro);
  cr::TruthMesh tb;
  tb.name = "b";
  tb.mesh = re.mesh;
  qs::family::SurfaceMap map;
  map.domain = qs::family::MapDomain::Surface;
  map.origins = re.origins;
  tb.map = map;
  tb.reference = r;
  const cr::GroundTruth truth({plain_truth(a, "a"), tb});
  EXPECT_GT(truth.tolerance(), 0);
  EXPECT_LT(truth.tolerance(), 0.02);
  // Vertex v of B is exactly its origin on R, whose (face, bary) on A gives the same point back.
  for (int v = 0; v < re.mesh.num_vertices(); v += 53) {
    const auto on_a = re.origins[v];
    const auto img = truth.map(0, 1, on_a);
    EXPECT_LT((qs::landmarks::position_of(re.mesh, img) - re.mesh.positions[v]).norm(), 1e-9);
  }
}

TEST(GroundTruth, MeshesWithoutACommonDomainAreRejected) {
  const auto fam = small_family(1, 2);
  try {
    cr::GroundTruth({sphere_truth(fam.shapes[0]), plain_truth(fam.shapes[0].mesh, "plain")});
    ADD_FAILURE();
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("either all or none"));
  }
  try {
    cr::GroundTruth({plain_truth(qs::shapes::icosphere(2), "ico"), plain_truth(qs::shapes::cube_sphere(4), "cube")});
    ADD_FAILURE();
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("cube does not have the connectivity of ico"));
  }
}

TEST(GroundTruth, ASphereMapMustCoverTheSphereOncePositively) {
  const auto fam = small_family(2, 5);
  // Every parameter mirrored: each face inverted on the sphere.
  cr::TruthMesh mirrored = sphere_truth(fam.shapes[1]);
  for (Vec3& d : mirrored.map->sphere) d.x() = -d.x();
  try {
    cr::GroundTruth({sphere_truth(fam.shapes[0]), mirrored});
    ADD_FAILURE();
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("is not a bijection of that mesh: 2000 faces"));
  }
  // An octahedron whose sphere map wraps twice around the z axis (the angle about z doubled):
  // every face stays positive, but the sphere is covered twice.
  qs::TriMesh octa;
  const int ring = 8;  // a bipyramid over a ring of 8
  octa.positions.push_back(Vec3(0, 0, 1));
  octa.positions.push_back(Vec3(0, 0, -1));
  for (int k = 0; k < ring; ++k) octa.positions.push_back(Vec3(std::cos(2 * M_PI * k / ring), std::sin(2 * M_PI * k / ring), 0));
  for (int k = 0; k < ring; ++k) {
    octa.faces.push_back({0, 2 + k, 2 + (k + 1) % ring});
    octa.faces.push_back({1, 2 + (k + 1) % ring, 2 + k});
  }
  cr::TruthMesh twice = plain_truth(octa, "twice");
  qs::family::SurfaceMap m;
  for (const Vec3& p : octa.positions) {
    const double a = 2 * std::atan2(p.y(), p.x()), r = std::hypot(p.x(), p.y());
    m.sphere.push_back(Vec3(r * std::cos(a), r * std::sin(a), p.z()).normalized());
  }
  twice.map = m;
  cr::TruthMesh once = plain_truth(octa, "once");
  qs::family::SurfaceMap m1;
  m1.sphere = octa.positions;
  once.map = m1;
  EXPECT_NO_THROW(cr::GroundTruth({once, once}));
  try {
    cr::GroundTruth({once, twice});
    ADD_FAILURE();
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("covers the sphere 2"));
  }
}

TEST(Measure, AMeshAgainstItselfIsExact) {
  const SelfPair self;
  cr::MeasureOptions o;
  o.samples = 20000;
  const auto pm = cr::measure_pair(self.truth, inputs_of(self.set), 0, 1, o);
  EXPECT_EQ(pm.samples, 20000);
  EXPECT_LT(pm.dissection.max, 1e-9);
  EXPECT_LT(pm.baseline.max, 1e-6);
  EXPECT_GT(pm.same_patch_share, 0.999);
  EXPECT_GE(pm.baseline_landmarks, 4);
  // Both maps are the identity: isometric on every face.
  EXPECT_FALSE(pm.distortion_on_b);
  EXPECT_NEAR(pm.distortion, 1, 1e-9);
  EXPECT_NEAR(pm.distortion_median, 1, 1e-9);
  EXPECT_NEAR(pm.truth_distortion, 1, 1e-9);
  EXPECT_EQ(pm.distortion_folded, 0);
  EXPECT_EQ(pm.truth_distortion_folded, 0);
}

// Through a remesh an exact map is off by the remesh's own error, which `remesh` measures: for
// the identity the two agree, and at level 0 there is none.
TEST(Measure, TheRemeshAloneIsWhatAnExactMapLosesThroughTheRemesh) {
  const SelfPair self;
  cr::MeasureOptions o;
  o.samples = 5000;
  EXPECT_EQ(cr::measure_pair(self.truth, inputs_of(self.set), 0, 1, o).remesh.max, 0);
  o.level = 2;
  const auto pm = cr::measure_pair(self.truth, inputs_of(self.set), 0, 1, o);
  EXPECT_GT(pm.remesh.mean, 0.01);  // a level-2 remesh cuts across the curved surface
  EXPECT_NEAR(pm.remesh.mean, pm.dissection.mean, 1e-9 * pm.dissection.mean);
  EXPECT_NEAR(pm.remesh.p95, pm.dissection.p95, 1e-9 * pm.dissection.p95);
  EXPECT_NEAR(pm.remesh.max, pm.dissection.max, 1e-9 * pm.dissection.max);
}

TEST(Measure, TheDistortionIgnoresSizeAndSeesAStretch) {
  const auto fam = small_family(1, 4);
  // B: A three times as large (an isometry up to size), then A stretched 1.6 times along x.
  for (const double sx : {3.0, 1.6}) {
    qs::family::FamilyShape b = fam.shapes[0];
    for (auto& p : b.mesh.positions) p = sx == 3.0 ? Vec3(3 * p) : Vec3(sx * p.x(), p.y(), p.z());
    const auto set = dissect_shapes({&fam.shapes[0], &b});
    const cr::GroundTruth truth({plain_truth(fam.shapes[0].mesh, "a"), plain_truth(b.mesh, "b")});
    cr::MeasureOptions o;
    o.samples = 2000;
    const auto pm = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
    EXPECT_EQ(pm.truth_distortion_folded, 0);
    // symDirichlet / 4 >= 1, equality for an isometry; the median is at most the mean here (a
    // few squeezed faces weigh on the mean only).
    EXPECT_GE(pm.distortion, 1 - 1e-12);
    EXPECT_GE(pm.distortion_median, 1 - 1e-12);
    if (sx == 3.0) {
      EXPECT_NEAR(pm.truth_distortion, 1, 1e-9);
    } else {
      // With the area scale s in [1 / sqrt(1.6), 1], a face's singular values lie between (s, s)
      // (normal to x) and (1.6 s, s) (x in its plane): symDirichlet / 4 at most 1.2375 (s = 1).
      EXPECT_GT(pm.truth_distortion, 1.01);
      EXPECT_LT(pm.truth_distortion, 1.2375);
      EXPECT_GT(pm.truth_distortion_median, 1.0);
    }
  }
}

TEST(Measure, AFamilyPairHasOrderedFiniteStatisticsIndependentOfThreads) {
  const auto fam = small_family(2, 6);
  const auto set = dissect_shapes({&fam.shapes[0], &fam.shapes[1]});
  const cr::GroundTruth truth({sphere_truth(fam.shapes[0]), sphere_truth(fam.shapes[1])});
  cr::MeasureOptions o;
  o.samples = 20000;
  o.threads = 1;
  const auto one = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
  o.threads = 3;
  const auto three = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
  EXPECT_EQ(one.dissection.mean, three.dissection.mean);
  EXPECT_EQ(one.dissection.max, three.dissection.max);
  EXPECT_EQ(one.baseline.p95, three.baseline.p95);
  EXPECT_EQ(one.same_patch_share, three.same_patch_share);
  for (const auto& s : {one.dissection, one.baseline}) {
    EXPECT_GT(s.mean, 0);
    EXPECT_LE(s.median, s.p95);
    EXPECT_LE(s.p95, s.max);
    EXPECT_LT(s.max, 100);
  }
  EXPECT_GT(one.same_patch_share, 0.5);
  EXPECT_LE(one.same_patch_share, 1.0);
  // Another seed samples other points: close but not equal figures.
  o.seed = 2;
  const auto other = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
  EXPECT_NE(other.dissection.mean, one.dissection.mean);
  EXPECT_NEAR(other.dissection.mean, one.dissection.mean, 0.1 * one.dissection.mean);
}

TEST(Measure, VertexErrorsAreExactForTheIdentityAndAgreeWithTheSamples) {
  const auto fam = small_family(2, 6);
  cr::MeasureOptions o;
  o.samples = 20000;
  {
    const auto set = dissect_shapes({&fam.shapes[0], &fam.shapes[0]});
    const cr::GroundTruth truth({plain_truth(fam.shapes[0].mesh, "a"), plain_truth(fam.shapes[0].mesh, "b")});
    EXPECT_TRUE(cr::measure_pair(truth, inputs_of(set), 0, 1, o).vertex_error.empty());  // not asked for
    o.vertex_errors = true;
    const auto pm = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
    ASSERT_EQ(pm.vertex_error.size(), fam.shapes[0].mesh.positions.size());
    ASSERT_EQ(pm.vertex_baseline_error.size(), pm.vertex_error.size());
    for (std::size_t v = 0; v < pm.vertex_error.size(); ++v) {
      EXPECT_LT(pm.vertex_error[v], 1e-9) << v;
      EXPECT_LT(pm.vertex_baseline_error[v], 1e-6) << v;
    }
  }
  const auto set = dissect_shapes({&fam.shapes[0], &fam.shapes[1]});
  const cr::GroundTruth truth({sphere_truth(fam.shapes[0]), sphere_truth(fam.shapes[1])});
  o.threads = 1;
  const auto one = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
  o.threads = 3;
  const auto three = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
  EXPECT_EQ(one.vertex_error, three.vertex_error);
  EXPECT_EQ(one.vertex_baseline_error, three.vertex_baseline_error);
  double sum = 0, base = 0, most = 0;
  for (std::size_t v = 0; v < one.vertex_error.size(); ++v) {
    ASSERT_TRUE(std::isfinite(one.vertex_error[v]) && one.vertex_error[v] >= 0) << v;
    sum += one.vertex_error[v];
    base += one.vertex_baseline_error[v];
    most = std::max(most, one.vertex_error[v]);
  }
  // The vertices sample the surface as the area samples do (the generator spaces them evenly per
  // unit area): the means agree within a quarter, and no vertex is worse than the worst sample by
  // more than the sampling's own spread.
  const double n = static_cast<double>(one.vertex_error.size());
  EXPECT_NEAR(sum / n, one.dissection.mean, 0.25 * one.dissection.mean);
  EXPECT_NEAR(base / n, one.baseline.mean, 0.25 * one.baseline.mean);
  EXPECT_LT(most, 1.5 * one.dissection.max);
  EXPECT_GT(most, 0.5 * one.dissection.max);
}

TEST(ErrorMap, ColoursRunFromBlueToRedAndTheFileReadsBack) {
  using C = std::array<unsigned char, 3>;
  EXPECT_EQ(cr::error_colour(0, 2), (C{0, 0, 255}));
  EXPECT_EQ(cr::error_colour(0.5, 2), (C{0, 255, 255}));
  EXPECT_EQ(cr::error_colour(1, 2), (C{0, 255, 0}));
  EXPECT_EQ(cr::error_colour(1.5, 2), (C{255, 255, 0}));
  EXPECT_EQ(cr::error_colour(2, 2), (C{255, 0, 0}));
  EXPECT_EQ(cr::error_colour(7, 2), (C{255, 0, 0}));
  EXPECT_EQ(cr::error_colour(-1, 2), (C{0, 0, 255}));
  EXPECT_EQ(cr::error_colour(std::nan(""), 2), (C{255, 0, 0}));

  const auto fam = small_family(1, 4);
  const qs::TriMesh& mesh = fam.shapes[0].mesh;
  cr::PairMeasure pm;
  const fs::path file = fs::temp_directory_path() / ("qs_error_map_" + std::to_string(::getpid()) + ".ply");
  EXPECT_THROW(cr::write_error_map(file, mesh, pm, 1.0), qs::InvalidInput);  // no vertex errors
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    pm.vertex_error.push_back(static_cast<double>(v % 7));
    pm.vertex_baseline_error.push_back(0.5);
  }
  EXPECT_THROW(cr::write_error_map(file, mesh, pm, 0.0), qs::InvalidInput);
  EXPECT_FALSE(fs::exists(file));
  cr::write_error_map(file, mesh, pm, 6.0);
  const auto read = qs::io::read_mesh(file);
  EXPECT_EQ(read.mesh.positions, mesh.positions);
  EXPECT_EQ(read.mesh.faces, mesh.faces);
  // Vertex 6's record: x y z (3 doubles), error 6, baseline 0.5 (floats), red.
  std::ifstream in(file, std::ios::binary);
  const std::string bytes(std::istreambuf_iterator<char>(in), {});
  const std::size_t record = 3 * 8 + 2 * 4 + 3, at = bytes.find("end_header\n") + 11 + 6 * record + 24;
  float e = 0, b = 0;
  std::memcpy(&e, bytes.data() + at, 4);
  std::memcpy(&b, bytes.data() + at + 4, 4);
  EXPECT_EQ(e, 6.0f);
  EXPECT_EQ(b, 0.5f);
  EXPECT_EQ(static_cast<unsigned char>(bytes[at + 8]), 255);
  EXPECT_EQ(static_cast<unsigned char>(bytes[at + 9]), 0);
  EXPECT_EQ(static_cast<unsigned char>(bytes[at + 10]), 0);
  fs::remove(file);
}

TEST(Measure, TheRemeshMapConvergesToTheChartMapWithTheLevel) {
  const auto fam = small_family(2, 6);
  const auto set = dissect_shapes({&fam.shapes[0], &fam.shapes[1]});
  const cr::GroundTruth truth({sphere_truth(fam.shapes[0]), sphere_truth(fam.shapes[1])});
  cr::MeasureOptions o;
  o.samples = 5000;
  const auto chart = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
  // The gap between the means is not monotone level by level (a difference of two means can
  // cross zero), but it shrinks from the coarsest to the finest level, to under 1% of the mean.
  double first = -1, previous = 1e300;
  for (int level : {1, 3, 5, 8}) {
    o.level = level;
    const auto pm = cr::measure_pair(truth, inputs_of(set), 0, 1, o);
    EXPECT_EQ(pm.level, level);
    const double gap = std::abs(pm.dissection.mean - chart.dissection.mean);
    if (first < 0) first = gap;
    previous = gap;
    EXPECT_EQ(pm.same_patch_share, chart.same_patch_share);  // the patch comes from A's chart
  }
  EXPECT_LT(previous, first);
  EXPECT_LT(previous, 0.01 * chart.dissection.mean);
  o.level = 13;
  EXPECT_THROW(cr::measure_pair(truth, inputs_of(set), 0, 1, o), qs::InvalidInput);
}

TEST(Measure, TheWrongMeshIsNamed) {
  const auto fam = small_family(2, 7);
  const auto set = dissect_shapes({&fam.shapes[0], &fam.shapes[1]});
  const cr::GroundTruth truth({sphere_truth(fam.shapes[1]), sphere_truth(fam.shapes[0])});
  try {
    cr::measure_pair(truth, inputs_of(set), 0, 1);
    ADD_FAILURE();
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("is not the mesh that was dissected"));
  }
}

TEST(LoadTruthMesh, ChecksTheMapAgainstTheMesh) {
  const auto dir = std::filesystem::temp_directory_path() / ("qs_truth_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto fam = small_family(1, 8);
  qs::io::write_mesh(dir / "s.obj", fam.shapes[0].mesh);
  qs::family::SurfaceMap m;
  m.sphere = fam.shapes[0].parameters;
  qs::family::write_surface_map(dir / "s.map.json", m);
  const auto t = cr::load_truth_mesh(dir / "s.obj", dir / "s.map.json");
  ASSERT_TRUE(t.map.has_value());
  EXPECT_EQ(t.map->sphere, fam.shapes[0].parameters);
  m.sphere.pop_back();
  qs::family::write_surface_map(dir / "short.map.json", m);
  try {
    cr::load_truth_mesh(dir / "s.obj", dir / "short.map.json");
    ADD_FAILURE();
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("short.map.json: 1001 vertices"));
  }
  std::filesystem::remove_all(dir);
}
