#include "qs/correspondence/correspondence.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/core/weighted.h"
#include "qs/landmarks/landmarks.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "qs/remesh/chart_sampler.h"

namespace qs::correspondence {

namespace {

std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}
double unit_double(std::uint64_t x) { return static_cast<double>(x >> 11) * 0x1.0p-53; }


landmarks::SurfacePoint surface_point_at(const TriMesh& m, int face, const Vec3& p) {
  const Tri& t = m.faces[face];
  const auto w = landmarks::closest_on_triangle(p, m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]);
  landmarks::SurfacePoint sp;
  sp.face = face;
  sp.bary = w;
  return sp;
}

/// A validated mesh's vertex -> the file's vertex id (inverse of vertex_map).
std::vector<int> file_ids(const mesh::ValidationResult& v) {
  std::vector<int> ids(v.mesh.positions.size(), -1);
  for (std::size_t u = 0; u < v.vertex_map.size(); ++u)
    if (v.vertex_map[u] >= 0) ids[v.vertex_map[u]] = static_cast<int>(u);
  return ids;
}

mesh::ValidationResult read_valid(const std::filesystem::path& file) {
  io::ReadResult r = io::read_mesh(file);
  mesh::ValidationResult v = mesh::validate(r.mesh);
  if (!v.report.accepted)
    throw InvalidInput("mesh rejected:\n" + mesh::format_report(file.string(), v.report));
  return v;
}

}  // namespace

TruthMesh load_truth_mesh(const std::filesystem::path& mesh_file, const std::optional<std::filesystem::path>& map_file) {
  TruthMesh t;
  t.name = mesh_file.string();
  const mesh::ValidationResult v = read_valid(mesh_file);
  t.mesh = v.mesh;
  if (!map_file) return t;
  family::SurfaceMap map = family::read_surface_map(*map_file);
  if (map.num_vertices() != v.report.input_vertices)
    throw InvalidInput(map_file->string() + ": " + std::to_string(map.num_vertices()) + " vertices, but " +
                       mesh_file.string() + " has " + std::to_string(v.report.input_vertices) +
                       " (is it the map of that mesh?)");
  const std::vector<int> ids = file_ids(v);
  family::SurfaceMap out = map;
  if (map.domain == family::MapDomain::Sphere) {
    out.sphere.resize(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) out.sphere[i] = map.sphere[ids[i]];
  } else {
    std::filesystem::path ref(map.reference);
    if (ref.is_relative()) ref = map_file->parent_path() / ref;
    const mesh::ValidationResult rv = read_valid(ref);
    if (rv.report.input_vertices != map.reference_vertices || rv.report.input_faces != map.reference_faces)
      throw InvalidInput(map_file->string() + ": its reference " + ref.string() + " has " +
                         std::to_string(rv.report.input_vertices) + " vertices and " +
                         std::to_string(rv.report.input_faces) + " faces, the map expects " +
                         std::to_string(map.reference_vertices) + " and " + std::to_string(map.reference_faces));
    out.origins.resize(ids.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
      out.origins[i] = map.origins[ids[i]];
      if (rv.report.orientation_flipped) std::swap(out.origins[i].bary[1], out.origins[i].bary[2]);
    }
    t.reference = rv.mesh;
  }
  t.map = std::move(out);
  return t;
}

struct GroundTruth::Impl {
  enum class Kind { Sphere, Identity, Surface };
  struct Side {
    Kind kind = Kind::Identity;
    std::unique_ptr<metro::SurfaceDistance> mesh_distance;   // Surface: closest point of the mesh
    std::unique_ptr<metro::SurfaceDistance> other_distance;  // Sphere: parameter mesh; Surface: reference
    TriMesh parameter_mesh;                                  // Sphere
    std::vector<std::array<int, 3>> neighbour;               // Sphere: across the edge opposite corner k
  };
  std::vector<TruthMesh> meshes;
  std::vector<Side> sides;
  double tolerance = 0, tolerance_mean = 0;

  struct DomainPoint {
    Vec3 d = Vec3::Zero();
    landmarks::SurfacePoint sp;
  };

  DomainPoint to_domain(int a, const landmarks::SurfacePoint& p) const {
    const TruthMesh& m = meshes[a];
    const Side& s = sides[a];
    DomainPoint dp;
    if (s.kind == Kind::Identity) {
      dp.sp = p;
    } else if (s.kind == Kind::Sphere) {
      const Tri& t = m.mesh.faces[p.face];
      dp.d = (p.bary[0] * m.map->sphere[t[0]] + p.bary[1] * m.map->sphere[t[1]] + p.bary[2] * m.map->sphere[t[2]])
                 .normalized();
    } else {
      const Vec3 x = landmarks::position_of(m.mesh, p);
      const auto c = s.other_distance->closest(x);
      dp.sp = surface_point_at(m.reference, c.face, c.point);
    }
    return dp;
  }

  landmarks::SurfacePoint from_domain(int b, const DomainPoint& dp) const {
    const TruthMesh& m = meshes[b];
    const Side& s = sides[b];
    if (s.kind == Kind::Identity) return dp.sp;
    if (s.kind == Kind::Surface) {
      const Vec3 y = landmarks::position_of(m.reference, dp.sp);
      const auto c = s.mesh_distance->closest(y);
      return surface_point_at(m.mesh, c.face, c.point);
    }
    // Sphere: walk from the face nearest to the parameter to the one the ray crosses.
    const auto& P = s.parameter_mesh.positions;
    int f = s.other_distance->closest(dp.d).face;
    for (int step = 0; step < 100000; ++step) {
      const Tri& t = s.parameter_mesh.faces[f];
      const Vec3 b(dp.d.dot(P[t[1]].cross(P[t[2]])), dp.d.dot(P[t[2]].cross(P[t[0]])), dp.d.dot(P[t[0]].cross(P[t[1]])));
      int worst = 0;
      b.minCoeff(&worst);
      if (b[worst] >= -1e-15 * b.cwiseAbs().maxCoeff() || b.sum() <= 0) {
        const Vec3 w = b.cwiseMax(0.0) / b.cwiseMax(0.0).sum();
        landmarks::SurfacePoint sp;
        sp.face = f;
        sp.bary = {w.x(), w.y(), w.z()};
        return sp;
      }
      f = s.neighbour[f][worst];
    }
    throw InvalidInput("ground truth: the walk on the parameter sphere of " + m.name +
                       " did not end: its sphere map is not a bijection");
  }
};

GroundTruth::GroundTruth(std::vector<TruthMesh> meshes) : impl_(std::make_unique<Impl>()) {
  impl_->meshes = std::move(meshes);
  const auto& ms = impl_->meshes;
  if (ms.size() < 2) throw InvalidInput("ground truth: at least 2 meshes are needed");
  const std::vector<Tri>* domain_faces = nullptr;
  std::string domain_owner;
  int spheres = 0;
  for (const TruthMesh& m : ms) {
    Impl::Side s;
    if (!m.map) {
      s.kind = Impl::Kind::Identity;
    } else if (m.map->domain == family::MapDomain::Sphere) {
      s.kind = Impl::Kind::Sphere;
      ++spheres;
      s.parameter_mesh.positions = m.map->sphere;
      s.parameter_mesh.faces = m.mesh.faces;
      int inverted = 0, first = -1;
      for (int f = 0; f < m.mesh.num_faces(); ++f) {
        const Tri& t = m.mesh.faces[f];
        const auto& P = s.parameter_mesh.positions;
        if (P[t[0]].dot(P[t[1]].cross(P[t[2]])) <= 0) {
          if (first < 0) first = f;
          ++inverted;
        }
      }
      if (inverted > 0)
        throw InvalidInput("ground truth: the sphere map of " + m.name + " is not a bijection of that mesh: " +
                           std::to_string(inverted) + " faces (first " + std::to_string(first) +
                           ") are inverted or flat on the sphere (is it the map of another mesh?)");
      // Positive faces could still wrap the sphere more than once: their solid angles (Van
      // Oosterom and Strackee) must add up to exactly one sphere.
      double solid = 0;
      for (const Tri& t : m.mesh.faces) {
        const auto& P = s.parameter_mesh.positions;
        const Vec3 &a = P[t[0]], &b = P[t[1]], &c = P[t[2]];
        solid += 2 * std::atan2(a.dot(b.cross(c)), 1 + a.dot(b) + b.dot(c) + c.dot(a));
      }
      if (std::abs(solid - 4 * 3.14159265358979323846) > 1e-6)
        throw InvalidInput("ground truth: the sphere map of " + m.name + " covers the sphere " +
                           std::to_string(solid / (4 * 3.14159265358979323846)) + " times; a map file must cover it once");
      s.other_distance = std::make_unique<metro::SurfaceDistance>(s.parameter_mesh, "parameter sphere");
      std::unordered_map<std::uint64_t, std::pair<int, int>> edge;  // directed edge -> (face, corner opposite)
      const int nf = m.mesh.num_faces();
      for (int f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) {
          const int u = m.mesh.faces[f][(k + 1) % 3], v = m.mesh.faces[f][(k + 2) % 3];
          edge[(static_cast<std::uint64_t>(u) << 32) | static_cast<std::uint32_t>(v)] = {f, k};
        }
      s.neighbour.assign(nf, {-1, -1, -1});
      for (int f = 0; f < nf; ++f)
        for (int k = 0; k < 3; ++k) {
          const int u = m.mesh.faces[f][(k + 1) % 3], v = m.mesh.faces[f][(k + 2) % 3];
          auto it = edge.find((static_cast<std::uint64_t>(v) << 32) | static_cast<std::uint32_t>(u));
          if (it == edge.end()) throw InvalidInput("ground truth: " + m.name + " is not a closed oriented mesh");
          s.neighbour[f][k] = it->second.first;
        }
    } else {
      s.kind = Impl::Kind::Surface;
      const double tol = 1e-9 * bounding_box(m.mesh.positions).diagonal();
      for (int v = 0; v < m.mesh.num_vertices(); ++v)
        if ((landmarks::position_of(m.reference, m.map->origins[v]) - m.mesh.positions[v]).norm() > tol)
          throw InvalidInput("ground truth: vertex " + std::to_string(v) + " of " + m.name +
                             " is not at its origin on the map's reference (is it the map of another mesh?)");
      s.mesh_distance = std::make_unique<metro::SurfaceDistance>(m.mesh, "mesh");
      s.other_distance = std::make_unique<metro::SurfaceDistance>(m.reference, "reference");
      metro::MetroOptions mo;
      mo.face_samples = 20000;
      mo.sample_vertices = true;
      const metro::MetroResult mr = metro::metro(m.mesh, m.reference, mo);
      impl_->tolerance = std::max(impl_->tolerance, mr.max);
      impl_->tolerance_mean = std::max(impl_->tolerance_mean, mr.mean);
    }
    if (s.kind != Impl::Kind::Sphere) {
      const std::vector<Tri>* faces = s.kind == Impl::Kind::Identity ? &m.mesh.faces : &m.reference.faces;
      if (!domain_faces) {
        domain_faces = faces;
        domain_owner = m.name;
      } else if (*faces != *domain_faces) {
        throw InvalidInput("ground truth: " + m.name + (s.kind == Impl::Kind::Identity ? "" : " (through its map's reference)") +
                           " does not have the connectivity of " + domain_owner +
                           "; without map files, meshes must share one face list (give each a map file, "
                           "e.g. <stem>.map.json)");
      }
    }
    impl_->sides.push_back(std::move(s));
  }
  if (spheres != 0 && spheres != static_cast<int>(ms.size()))
    throw InvalidInput("ground truth: " + std::to_string(spheres) + " of " + std::to_string(ms.size()) +
                       " meshes have sphere maps; either all or none must (a sphere and a surface cannot be compared)");
}

GroundTruth::~GroundTruth() = default;
GroundTruth::GroundTruth(GroundTruth&&) noexcept = default;
GroundTruth& GroundTruth::operator=(GroundTruth&&) noexcept = default;
int GroundTruth::size() const { return static_cast<int>(impl_->meshes.size()); }
const TruthMesh& GroundTruth::mesh(int i) const { return impl_->meshes.at(i); }
double GroundTruth::tolerance() const { return impl_->tolerance; }
double GroundTruth::tolerance_mean() const { return impl_->tolerance_mean; }

landmarks::SurfacePoint GroundTruth::map(int a, int b, const landmarks::SurfacePoint& p) const {
  return impl_->from_domain(b, impl_->to_domain(a, p));
}

std::vector<std::pair<std::string, Vec3>> dissection_landmarks(const dissect::Dissection& d) {
  std::vector<std::pair<std::string, Vec3>> out;
  const int nv = d.chart.mesh.num_vertices();
  for (int k = 0; k < 4; ++k)
    if (d.seeds[k] >= 0 && d.seeds[k] < nv) out.emplace_back("seed" + std::to_string(k), d.chart.mesh.positions[d.seeds[k]]);
  for (const auto& f : d.features)
    if (f.vertex >= 0 && f.vertex < nv) out.emplace_back(f.name, d.chart.mesh.positions[f.vertex]);
  return out;
}

namespace {

ErrorStats stats(std::vector<double> e) {
  ErrorStats s;
  if (e.empty()) return s;
  double sum = 0;
  for (double x : e) sum += x;  // in sample order: deterministic
  s.mean = sum / e.size();
  std::sort(e.begin(), e.end());
  auto q = [&](double f) { return e[std::min(e.size() - 1, static_cast<std::size_t>(std::floor(f * (e.size() - 1) + 0.5)))]; };
  s.median = q(0.5);
  s.p95 = q(0.95);
  s.max = e.back();
  return s;
}

// Where a map puts one vertex of A: the point on B and B's unit normal there.
struct Image {
  Vec3 point = Vec3::Zero(), normal = Vec3::Zero();
};

struct Distortion {
  double mean = 0, median = 0;  // area-weighted
  int folded = 0;
};

// The 2x2 coordinates of a triangle's edges u, v in an orthonormal frame of its plane (normal n).
Eigen::Matrix2d in_plane(const Vec3& u, const Vec3& v, const Vec3& n) {
  const Vec3 x = u.normalized(), y = n.normalized().cross(x);
  Eigen::Matrix2d p;
  p << u.dot(x), v.dot(x), u.dot(y), v.dot(y);
  return p;
}

// PairMeasure::distortion of the map a -> image (one image per vertex of a), scaled by `scale`.
Distortion distortion_of(const TriMesh& a, const std::vector<Image>& image, double scale) {
  std::vector<std::pair<double, double>> energy;  // (symDirichlet / 4, area) per face
  energy.reserve(a.faces.size());
  Distortion out;
  for (const Tri& t : a.faces) {
    const Vec3 e1 = a.positions[t[1]] - a.positions[t[0]], e2 = a.positions[t[2]] - a.positions[t[0]];
    const Vec3 n = e1.cross(e2);
    if (!(n.norm() > 0)) continue;  // a zero-area face of A weighs nothing
    const Vec3 f1 = image[t[1]].point - image[t[0]].point, f2 = image[t[2]].point - image[t[0]].point;
    const Vec3 m = f1.cross(f2);
    if (!(m.norm() > 0) || !(m.dot(image[t[0]].normal + image[t[1]].normal + image[t[2]].normal) > 0)) {
      ++out.folded;
      continue;
    }
    const Eigen::Matrix2d j = scale * in_plane(f1, f2, m) * in_plane(e1, e2, n).inverse();
    const double d = j.determinant();
    energy.emplace_back(j.squaredNorm() * (1 + 1 / (d * d)) / 4, 0.5 * n.norm());
  }
  double sum = 0, area = 0;
  for (const auto& [e, w] : energy) {  // in face order: deterministic
    sum += w * e;
    area += w;
  }
  if (!(area > 0)) return out;
  out.mean = sum / area;
  std::sort(energy.begin(), energy.end());
  out.median = value_at_weight(energy, 0.5 * area);
  return out;
}

// The unit normal of face f (zero for a degenerate face).
Vec3 face_normal(const TriMesh& m, int f) {
  const Tri& t = m.faces[f];
  const Vec3 n = (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
  return n.norm() > 0 ? Vec3(n.normalized()) : Vec3(Vec3::Zero());
}

struct DistortionPair {
  Distortion dissection, truth;
};

// Both maps from mesh s (its chart cs) to mesh t (its chart's sampler), at s's vertices (the
// chart's first vertices are the input's): the dissection's by the first wedge of each vertex,
// the exact one by a face of s at that vertex; then distortion_of on s's faces, scaled to equal
// areas.
DistortionPair map_distortions(const GroundTruth& truth, const dissect::Chart& cs, int s, int t,
                               const remesh::ChartSampler& sampler_t, int threads) {
  const TriMesh& ms = truth.mesh(s).mesh;
  const TriMesh& mt = truth.mesh(t).mesh;
  const dissect::Chart& ct = sampler_t.chart();
  const int nv = ms.num_vertices();
  std::vector<int> wedge(nv, -1), corner(nv, -1);
  for (int f = cs.mesh.num_faces() - 1; f >= 0; --f)
    for (int k = 0; k < 3; ++k)
      if (cs.mesh.faces[f][k] < nv) wedge[cs.mesh.faces[f][k]] = 3 * f + k;
  for (int f = ms.num_faces() - 1; f >= 0; --f)
    for (int k = 0; k < 3; ++k) corner[ms.faces[f][k]] = 3 * f + k;
  std::vector<Image> by_dissection(nv), by_truth(nv);
  auto map_vertex = [&](int v) {
    if (wedge[v] >= 0) {
      const int f = wedge[v] / 3, patch = cs.face_patch[f];
      const Vec2 st = cs.face_uv[f][wedge[v] % 3].cwiseMax(0.0).cwiseMin(1.0);
      by_dissection[v].point = sampler_t.point(patch, st);
      by_dissection[v].normal = face_normal(ct.mesh, sampler_t.locate(patch, st).face);
    }
    if (corner[v] >= 0) {
      landmarks::SurfacePoint sp;
      sp.face = corner[v] / 3;
      sp.bary = {0.0, 0.0, 0.0};
      sp.bary[corner[v] % 3] = 1.0;
      const landmarks::SurfacePoint image = truth.map(s, t, sp);
      by_truth[v].point = landmarks::position_of(mt, image);
      by_truth[v].normal = face_normal(mt, image.face);
    }
  };
  constexpr int kVertexChunk = 1024;
  parallel_for((nv + kVertexChunk - 1) / kVertexChunk, threads, Context{}, [&](int c) {
    for (int v = c * kVertexChunk; v < std::min(nv, (c + 1) * kVertexChunk); ++v) map_vertex(v);
  });
  const double area_s = surface_area(ms), area_t = surface_area(mt);
  const double scale = area_t > 0 ? std::sqrt(area_s / area_t) : 1.0;
  return {distortion_of(ms, by_dissection, scale), distortion_of(ms, by_truth, scale)};
}

}  // namespace

PairMeasure measure_pair(const GroundTruth& truth, const std::vector<DissectedInput>& inputs, int a, int b,
                         const MeasureOptions& options, const Context& context) {
  if (options.samples < 1) throw InvalidInput("correspondence: samples must be at least 1");
  if (options.level < 0 || options.level > 12)
    throw InvalidInput("correspondence: level " + std::to_string(options.level) + " is outside [0, 12]");
  if (a < 0 || b < 0 || a >= truth.size() || b >= truth.size() || static_cast<int>(inputs.size()) != truth.size() || a == b)
    throw InvalidInput("correspondence: a pair of two different meshes of the set is needed");
  for (int i : {a, b}) {
    const TriMesh& m = truth.mesh(i).mesh;
    const dissect::Chart& c = *inputs[i].chart;
    bool same = c.mesh.num_vertices() >= m.num_vertices();
    for (int v = 0; same && v < m.num_vertices(); ++v) same = c.mesh.positions[v] == m.positions[v];
    if (!same)
      throw InvalidInput("correspondence: " + truth.mesh(i).name + " is not the mesh that was dissected (its chart's "
                         "first vertices differ)");
  }
  const dissect::Chart& ca = *inputs[a].chart;
  const dissect::Chart& cb = *inputs[b].chart;
  if (ca.patches.size() != cb.patches.size())
    throw InvalidInput("correspondence: the charts of " + truth.mesh(a).name + " and " + truth.mesh(b).name +
                       " have different patch counts");
  for (std::size_t p = 0; p < ca.patches.size(); ++p)
    if (ca.patches[p].name != cb.patches[p].name)
      throw InvalidInput("correspondence: patch " + std::to_string(p) + " is " + ca.patches[p].name + " in one chart and " +
                         cb.patches[p].name + " in the other");

  const remesh::ChartSampler sampler(cb, context.without_progress());
  const metro::SurfaceDistance on_a(truth.mesh(a).mesh, "A");
  const metro::SurfaceDistance on_b_chart(cb.mesh, "B");
  const TriMesh& mb = truth.mesh(b).mesh;

  // The baseline's similarity, from the landmarks both meshes have.
  std::vector<Vec3> src, dst;
  for (const auto& [name, p] : inputs[a].landmarks)
    for (const auto& [name_b, q] : inputs[b].landmarks)
      if (name == name_b) {
        src.push_back(p);
        dst.push_back(q);
      }
  Eigen::Matrix4d similarity = Eigen::Matrix4d::Identity();
  if (src.size() >= 3) {
    similarity = fit_similarity(src, dst);
  }

  // Where the dissection sends A's point (patch, st) on B: B's chart at (patch, st), or the point of
  // B's level-n remesh triangle at (u, v) (the cell cut by qs-remesh's diagonal rule).
  auto map_point = [&](int patch, const Vec2& st, int& hint) -> Vec3 {
    if (options.level == 0) return sampler.point(patch, st, hint);
    const int cells = 1 << options.level;
    const int i = std::min(cells - 1, static_cast<int>(st.x() * cells));
    const int j = std::min(cells - 1, static_cast<int>(st.y() * cells));
    const double fu = st.x() * cells - i, fv = st.y() * cells - j;
    auto grid = [&](int gi, int gj) {
      return sampler.point(patch, Vec2(static_cast<double>(gi) / cells, static_cast<double>(gj) / cells), hint);
    };
    const Vec3 p00 = grid(i, j), p10 = grid(i + 1, j), p11 = grid(i + 1, j + 1), p01 = grid(i, j + 1);
    if ((2 * i < cells) == (2 * j < cells))  // diagonal (i,j)-(i+1,j+1)
      return fu >= fv ? Vec3(p00 + fu * (p10 - p00) + fv * (p11 - p10)) : Vec3(p00 + fv * (p01 - p00) + fu * (p11 - p01));
    return fu + fv <= 1 ? Vec3(p00 + fu * (p10 - p00) + fv * (p01 - p00))  // diagonal (i+1,j)-(i,j+1)
                        : Vec3(p11 + (1 - fu) * (p01 - p11) + (1 - fv) * (p10 - p11));
  };

  // Samples uniformly per unit area on A's chart (A's surface): systematic along the faces.
  const int nf = ca.mesh.num_faces();
  std::vector<double> cumulative(nf + 1, 0.0);
  for (int f = 0; f < nf; ++f) cumulative[f + 1] = cumulative[f] + face_area(ca.mesh, f);
  const double total = cumulative[nf];
  if (!(total > 0)) throw InvalidInput("correspondence: " + truth.mesh(a).name + " has zero area");
  const long n = options.samples;
  std::vector<double> err(n), base_err(n), remesh_err(n);
  std::vector<double> same(n);
  const Box3 box = bounding_box(cb.mesh.positions);
  const double diag = box.diagonal();
  // One point x of A, at (patch, st) in A's chart and `on_input` on A's input mesh: the dissection's
  // error and the baseline's (% of the diagonal), and the patch of B's chart nearest its exact image.
  struct PointMeasure {
    double error, baseline;
    int exact_patch;
    double remesh;  // at level n >= 1: the exact image against B's remesh at the image's own (u, v)
  };
  auto measure_point = [&](const Vec3& x, int patch, const Vec2& st, const landmarks::SurfacePoint& on_input,
                           int& hint) {
    const Vec3 mapped = map_point(patch, st, hint);
    const Vec3 exact = landmarks::position_of(mb, truth.map(a, b, on_input));
    const Vec3 moved = (similarity * x.homogeneous()).head<3>();
    const auto at_exact = on_b_chart.closest(exact);
    double remesh = 0;
    if (options.level > 0) {
      const Tri& t = cb.mesh.faces[at_exact.face];
      const auto w = landmarks::closest_on_triangle(exact, cb.mesh.positions[t[0]], cb.mesh.positions[t[1]],
                                                    cb.mesh.positions[t[2]]);
      const auto& fuv = cb.face_uv[at_exact.face];
      const Vec2 own = (w[0] * fuv[0] + w[1] * fuv[1] + w[2] * fuv[2]).cwiseMax(0.0).cwiseMin(1.0);
      int own_hint = -1;
      remesh = 100 * (map_point(cb.face_patch[at_exact.face], own, own_hint) - exact).norm() / diag;
    }
    return PointMeasure{100 * (mapped - exact).norm() / diag,
                        100 * (on_b_chart.closest(moved).point - exact).norm() / diag,
                        cb.face_patch[at_exact.face], remesh};
  };

  constexpr long kChunk = 1024;
  const long chunks = (n + kChunk - 1) / kChunk;
  std::atomic<long> done{0};
  parallel_for(static_cast<int>(chunks), options.threads, context, [&](int c) {
    int hint = -1;
    for (long k = c * kChunk; k < std::min(n, (c + 1) * kChunk); ++k) {
      const std::uint64_t r0 = splitmix64(options.seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(k));
      const double target = (static_cast<double>(k) + unit_double(r0)) / static_cast<double>(n) * total;
      int f = static_cast<int>(std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin()) - 1;
      f = std::clamp(f, 0, nf - 1);
      while (f > 0 && cumulative[f + 1] - cumulative[f] <= 0) --f;
      const double s1 = std::sqrt(unit_double(splitmix64(r0))), s2 = unit_double(splitmix64(r0 ^ 0x5bd1e995ULL));
      const Vec3 beta(1 - s1, s1 * (1 - s2), s1 * s2);
      const Tri& t = ca.mesh.faces[f];
      const Vec3 x = beta[0] * ca.mesh.positions[t[0]] + beta[1] * ca.mesh.positions[t[1]] + beta[2] * ca.mesh.positions[t[2]];
      const Vec2 uv = beta[0] * ca.face_uv[f][0] + beta[1] * ca.face_uv[f][1] + beta[2] * ca.face_uv[f][2];
      const int patch = ca.face_patch[f];
      const Vec2 st = uv.cwiseMax(0.0).cwiseMin(1.0);
      const auto ca_closest = on_a.closest(x);
      const PointMeasure m =
          measure_point(x, patch, st, surface_point_at(truth.mesh(a).mesh, ca_closest.face, ca_closest.point), hint);
      err[k] = m.error;
      remesh_err[k] = m.remesh;
      same[k] = m.exact_patch == patch ? 1.0 : 0.0;
      base_err[k] = m.baseline;
    }
    context.report("correspondence", static_cast<double>(++done) / chunks);
  });

  PairMeasure pm;
  if (options.vertex_errors) {
    // At A's input vertices (the chart's first ones), through the wedge of each one's first chart
    // face; the truth at a vertex through an input face around it.
    const TriMesh& ma = truth.mesh(a).mesh;
    const int nv = ma.num_vertices();
    std::vector<int> chart_face(nv, -1), chart_corner(nv, -1), input_face(nv, -1);
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) {
        const int v = ca.mesh.faces[f][k];
        if (v < nv && chart_face[v] < 0) chart_face[v] = f, chart_corner[v] = k;
      }
    for (int f = 0; f < ma.num_faces(); ++f)
      for (int v : ma.faces[f])
        if (input_face[v] < 0) input_face[v] = f;
    pm.vertex_error.assign(nv, 0.0);
    pm.vertex_baseline_error.assign(nv, 0.0);
    pm.vertex_patch.assign(nv, -1);
    pm.vertex_exact_patch.assign(nv, -1);
    constexpr int kVertexChunk = 256;
    parallel_for((nv + kVertexChunk - 1) / kVertexChunk, options.threads, context, [&](int c) {
      int hint = -1;
      for (int v = c * kVertexChunk; v < std::min(nv, (c + 1) * kVertexChunk); ++v) {
        if (chart_face[v] < 0 || input_face[v] < 0) continue;  // unused vertex (validation drops them)
        const int f = chart_face[v];
        const Vec3& x = ma.positions[v];
        const Vec2 st = ca.face_uv[f][chart_corner[v]].cwiseMax(0.0).cwiseMin(1.0);
        const PointMeasure m = measure_point(x, ca.face_patch[f], st, surface_point_at(ma, input_face[v], x), hint);
        pm.vertex_error[v] = m.error;
        pm.vertex_baseline_error[v] = m.baseline;
        pm.vertex_patch[v] = ca.face_patch[f];
        pm.vertex_exact_patch[v] = m.exact_patch;
      }
    });
  }
  pm.a = a;
  pm.b = b;
  pm.level = options.level;
  pm.samples = n;
  pm.diagonal = diag;
  pm.dissection = stats(err);
  pm.baseline = stats(base_err);
  pm.remesh = stats(remesh_err);
  double s = 0;
  for (double v : same) s += v;
  pm.same_patch_share = s / n;
  {
    std::vector<char> seen(ca.mesh.num_vertices(), 0);
    double sum = 0;
    int count = 0;
    for (std::size_t p = 0; p < ca.patches.size(); ++p)
      for (int m = 0; m < 4; ++m) {
        const int va = ca.patches[p].corners[m];
        if (va < 0 || va >= ca.mesh.num_vertices() || seen[va]) continue;
        seen[va] = 1;
        const auto closest = on_a.closest(ca.mesh.positions[va]);
        const Vec3 exact = landmarks::position_of(
            mb, truth.map(a, b, surface_point_at(truth.mesh(a).mesh, closest.face, closest.point)));
        const double d = 100 * (cb.mesh.positions[cb.patches[p].corners[m]] - exact).norm() / diag;
        sum += d;
        pm.corner_max = std::max(pm.corner_max, d);
        ++count;
      }
    pm.corner_mean = count > 0 ? sum / count : 0;
  }
  {
    // Seen from the mesh whose vertices the truth maps exactly: A, unless A is the reference of a
    // re-tessellated B ("surface" map: exact at B's vertices, by closest point at A's).
    const bool from_b = !truth.mesh(a).map && truth.mesh(b).map;
    const DistortionPair d = from_b ? map_distortions(truth, *inputs[b].chart, b, a, remesh::ChartSampler(ca), options.threads)
                                    : map_distortions(truth, ca, a, b, sampler, options.threads);
    pm.distortion_on_b = from_b;
    pm.distortion = d.dissection.mean;
    pm.distortion_median = d.dissection.median;
    pm.distortion_folded = d.dissection.folded;
    pm.truth_distortion = d.truth.mean;
    pm.truth_distortion_median = d.truth.median;
    pm.truth_distortion_folded = d.truth.folded;
  }
  pm.baseline_landmarks = src.size() >= 3 ? static_cast<int>(src.size()) : 0;
  pm.truth_tolerance = 100 * truth.tolerance() / diag;
  pm.truth_tolerance_mean = 100 * truth.tolerance_mean() / diag;
  return pm;
}

std::vector<int> worst_vertices(const PairMeasure& measure, int count) {
  if (count < 0) throw InvalidInput("worst_vertices: count " + std::to_string(count) + " is negative");
  const std::vector<double>& e = measure.vertex_error;
  std::vector<int> order;
  for (int v = 0; v < static_cast<int>(e.size()); ++v)
    if (measure.vertex_patch.empty() || measure.vertex_patch[v] >= 0) order.push_back(v);
  const size_t k = std::min<size_t>(order.size(), static_cast<size_t>(count));
  std::partial_sort(order.begin(), order.begin() + static_cast<long>(k), order.end(),
                    [&](int a, int b) { return e[a] != e[b] ? e[a] > e[b] : a < b; });
  order.resize(k);
  return order;
}

std::array<unsigned char, 3> error_colour(double error, double scale) {
  // blue, cyan, green, yellow, red at 0, 1/4, 1/2, 3/4, 1 of the scale
  static constexpr double kStops[5][3] = {{0, 0, 255}, {0, 255, 255}, {0, 255, 0}, {255, 255, 0}, {255, 0, 0}};
  const double t = std::clamp(std::isfinite(error) && scale > 0 ? error / scale : 1.0, 0.0, 1.0) * 4;
  const int i = std::min(3, static_cast<int>(t));
  const double f = t - i;
  std::array<unsigned char, 3> c{};
  for (int k = 0; k < 3; ++k)
    c[k] = static_cast<unsigned char>(std::lround((1 - f) * kStops[i][k] + f * kStops[i + 1][k]));
  return c;
}

void write_error_map(const std::filesystem::path& path, const TriMesh& mesh, const PairMeasure& measure,
                     double scale) {
  const std::size_t nv = mesh.positions.size();
  if (measure.vertex_error.size() != nv || measure.vertex_baseline_error.size() != nv)
    throw InvalidInput("error map " + path.string() + ": " + std::to_string(measure.vertex_error.size()) +
                       " vertex errors for a mesh of " + std::to_string(nv) + " vertices (measure with vertex_errors)");
  if (!(scale > 0) || !std::isfinite(scale))
    throw InvalidInput("error map " + path.string() + ": the colour scale must be a positive number");
  AtomicFile file(path);
  std::ostream& out = file.stream();
  auto put = [&out](auto value) { out.write(reinterpret_cast<const char*>(&value), sizeof(value)); };  // little endian
  out << "ply\nformat binary_little_endian 1.0\n"
      << "comment qs correspondence error map: A's mesh, per vertex the error of the dissection's map and of the "
         "similarity + nearest-point baseline, % of B's bounding-box diagonal\n"
      << "comment colour scale: red at " << scale << "%\n"
      << "element vertex " << nv << "\nproperty double x\nproperty double y\nproperty double z\n"
      << "property float error\nproperty float baseline_error\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << mesh.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (std::size_t v = 0; v < nv; ++v) {
    for (int k = 0; k < 3; ++k) put(mesh.positions[v][k]);
    put(static_cast<float>(measure.vertex_error[v]));
    put(static_cast<float>(measure.vertex_baseline_error[v]));
    for (unsigned char c : error_colour(measure.vertex_error[v], scale)) put(c);
  }
  for (const Tri& t : mesh.faces) {
    put(static_cast<std::uint8_t>(3));
    for (int k = 0; k < 3; ++k) put(static_cast<std::int32_t>(t[k]));
  }
  file.commit();
}

dissect::MeshToDissect dissect_input(const family::FamilyShape& shape) {
  dissect::MeshToDissect m;
  m.mesh = &shape.mesh;
  m.name = shape.name;
  std::array<landmarks::SurfacePoint, 4> seeds;
  for (int k = 0; k < 4; ++k) seeds[k] = shape.seeds[k].where;
  m.seed_points = seeds;
  for (const auto& f : shape.features) m.features.push_back({f.name, -1, f.where});
  return m;
}

}  // namespace qs::correspondence
