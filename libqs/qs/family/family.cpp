#include "qs/family/family.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/family/sphere_hull.h"
#include "qs/mesh/validate.h"

namespace qs::family {

namespace {

constexpr double kPi = 3.14159265358979323846;
/// Samplings of a shape's parameters tried before giving up (see make_mesh).
constexpr int kSamplingAttempts = 8;

/// splitmix64: our own generator, so that the numbers do not depend on the standard library.
struct Rng {
  std::uint64_t state;
  explicit Rng(std::uint64_t seed) : state(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }     ///< [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  Vec3 direction() {  ///< uniform on the unit sphere
    const double z = uniform(-1, 1), phi = uniform(0, 2 * kPi), s = std::sqrt(std::max(0.0, 1 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
  }
};

std::uint64_t mix(std::uint64_t a, std::uint64_t b) {
  Rng r(a * 0x9e3779b97f4a7c15ULL ^ (b + 0x632be59bd9b4e019ULL));
  r.next();
  return r.next();
}

Vec3 any_perpendicular(const Vec3& a) {
  const Vec3 t = std::abs(a.x()) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
  return a.cross(t).normalized();
}

struct Limb {
  std::string name;
  Vec3 axis;            ///< common to the family (unit)
  double length = 1;    ///< radial extension at the tip
  double sigma = 0.2;   ///< angular width (radians) of the Gaussian profile
  double bend = 0;      ///< sideways displacement of the tip, as a fraction of the length
  Vec3 bend_dir = Vec3::UnitZ();  ///< unit, perpendicular to the axis
};

struct Bulge {
  Vec3 centre;
  double height = 0;   ///< relative change of the body radius at the centre
  double width = 0.3;  ///< angular width (radians)
};

/// Everything that defines the smooth map S_i of one shape.
struct ShapeParams {
  Vec3 semi_axes{1.0, 0.55, 0.5};
  std::vector<Limb> limbs;
  std::vector<Bulge> bulges;
  Vec3 scale{1, 1, 1};
  double twist = 0;  ///< radians per unit of x, about the x axis
  double wave = 0;   ///< amplitude of the sine deformation
  std::array<Vec3, 3> wave_k{Vec3::UnitX(), Vec3::UnitY(), Vec3::UnitZ()};
  Vec3 wave_phase = Vec3::Zero();
};

struct Base {
  int limbs = 4;
  Vec3 semi_axes;
  std::vector<Limb> limbs_base;
};

void check_options(const FamilyOptions& o) {
  auto fail = [](const std::string& m) { throw InvalidInput("family: " + m); };
  if (o.shapes < 1 || o.shapes > 256) fail("shapes = " + std::to_string(o.shapes) + " is outside [1, 256]");
  if (o.faces < 200 || o.faces > 2000000 || o.faces % 2 != 0)
    fail("faces = " + std::to_string(o.faces) + ": expected an even count in [200, 2000000] (a closed "
         "genus-0 triangle mesh has F = 2V - 4)");
  if (o.limbs != 0 && (o.limbs < 4 || o.limbs > 6))
    fail("limbs = " + std::to_string(o.limbs) + ": expected 4, 5 or 6 (or 0: chosen by the seed)");
  if (!(o.variation >= 0 && o.variation <= 2))
    fail("variation = " + std::to_string(o.variation) + " is outside [0, 2]");
}

Base make_base(const FamilyOptions& o) {
  Rng rng(mix(o.seed, 0xba5e));
  Base b;
  b.limbs = o.limbs != 0 ? o.limbs : 4 + static_cast<int>(rng.next() % 3);
  b.semi_axes = Vec3(1.0 * rng.uniform(0.95, 1.05), 0.55 * rng.uniform(0.95, 1.05), 0.5 * rng.uniform(0.95, 1.05));
  auto jitter = [&](Vec3 v) { return (v.normalized() + 0.05 * rng.direction()).normalized(); };
  const char* leg_names[4] = {"leg_front_left", "leg_front_right", "leg_hind_left", "leg_hind_right"};
  const double sx[4] = {1, 1, -1, -1}, sy[4] = {1, -1, 1, -1};
  for (int k = 0; k < 4; ++k) {
    Limb l;
    l.name = leg_names[k];
    l.axis = jitter(Vec3(0.55 * sx[k], 0.45 * sy[k], -0.7));
    l.length = 1.1 * rng.uniform(0.9, 1.1);
    l.sigma = 0.19 * rng.uniform(0.9, 1.1);
    b.limbs_base.push_back(l);
  }
  if (b.limbs >= 5) {
    Limb l;
    l.name = "head";
    l.axis = jitter(Vec3(1, 0, 0.35));
    l.length = 0.55 * rng.uniform(0.9, 1.1);
    l.sigma = 0.3 * rng.uniform(0.9, 1.1);
    b.limbs_base.push_back(l);
  }
  if (b.limbs >= 6) {
    Limb l;
    l.name = "tail";
    l.axis = jitter(Vec3(-1, 0, 0.25));
    l.length = 1.2 * rng.uniform(0.9, 1.1);
    l.sigma = 0.12 * rng.uniform(0.9, 1.1);
    b.limbs_base.push_back(l);
  }
  return b;
}

ShapeParams make_shape(const FamilyOptions& o, const Base& base, int index) {
  Rng rng(mix(o.seed, 1000 + static_cast<std::uint64_t>(index)));
  const double v = o.variation;
  ShapeParams s;
  s.semi_axes = base.semi_axes;
  for (Limb l : base.limbs_base) {
    l.length *= std::exp(0.25 * v * rng.uniform(-1, 1));
    l.sigma *= 1 + 0.15 * v * rng.uniform(-1, 1);
    l.bend = 0.3 * v * rng.uniform(-1, 1);
    const Vec3 p = any_perpendicular(l.axis), q = l.axis.cross(p);
    const double a = rng.uniform(0, 2 * kPi);
    l.bend_dir = std::cos(a) * p + std::sin(a) * q;
    s.limbs.push_back(l);
  }
  for (int m = 0; m < 3; ++m) s.bulges.push_back({rng.direction(), v * rng.uniform(-0.12, 0.18), rng.uniform(0.25, 0.4)});
  s.scale = Vec3(1 + 0.15 * v * rng.uniform(-1, 1), 1 + 0.15 * v * rng.uniform(-1, 1), 1 + 0.15 * v * rng.uniform(-1, 1));
  s.twist = 0.3 * v * rng.uniform(-1, 1);
  s.wave = 0.04 * v;
  for (Vec3& k : s.wave_k) k = 1.5 * rng.direction();
  s.wave_phase = Vec3(rng.uniform(0, 2 * kPi), rng.uniform(0, 2 * kPi), rng.uniform(0, 2 * kPi));
  return s;
}

/// The smooth map S_i of the header.
Vec3 surface_point(const ShapeParams& s, const Vec3& d) {
  const Vec3 e = d.cwiseQuotient(s.semi_axes);
  double r = 1.0 / e.norm();  // the ellipsoid along d
  double bulge = 1;
  for (const Bulge& b : s.bulges) bulge += b.height * std::exp((d.dot(b.centre) - 1) / (b.width * b.width));
  r *= bulge;
  Vec3 bend = Vec3::Zero();
  for (const Limb& l : s.limbs) {
    const double g = std::exp((d.dot(l.axis) - 1) / (l.sigma * l.sigma));
    r += l.length * g;
    bend += l.bend * l.length * g * g * l.bend_dir;
  }
  Vec3 p = r * d + bend;
  p = p.cwiseProduct(s.scale);
  const double a = s.twist * p.x(), c = std::cos(a), sn = std::sin(a);
  p = Vec3(p.x(), c * p.y() - sn * p.z(), sn * p.y() + c * p.z());
  p += s.wave * Vec3(std::sin(s.wave_k[0].dot(p) + s.wave_phase.x()), std::sin(s.wave_k[1].dot(p) + s.wave_phase.y()),
                     std::sin(s.wave_k[2].dot(p) + s.wave_phase.z()));
  return p;
}

/// The surface's tangent vectors at d along an orthonormal tangent basis of the sphere (central
/// differences), and their cross product (its norm is the area element).
Vec3 surface_normal(const ShapeParams& s, const Vec3& d) {
  const Vec3 t1 = any_perpendicular(d), t2 = d.cross(t1);
  const double h = 1e-5;
  const Vec3 du = surface_point(s, (d + h * t1).normalized()) - surface_point(s, (d - h * t1).normalized());
  const Vec3 dv = surface_point(s, (d + h * t2).normalized()) - surface_point(s, (d - h * t2).normalized());
  return du.cross(dv) / (4 * h * h);
}

double area_element(const ShapeParams& s, const Vec3& d) { return surface_normal(s, d).norm(); }

std::vector<Vec3> fibonacci(int n) {
  std::vector<Vec3> r(n);
  const double ga = kPi * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - (2.0 * i + 1) / n, s = std::sqrt(std::max(0.0, 1 - z * z));
    r[i] = Vec3(s * std::cos(ga * i), s * std::sin(ga * i), z);
  }
  return r;
}

/// Points on the sphere with a density proportional to the area element, kept apart by a minimum
/// spacing proportional to the local mean spacing (dart throwing).
std::vector<Vec3> sample_parameters(const ShapeParams& s, int count, std::uint64_t seed) {
  const std::vector<Vec3> probe = fibonacci(20000);
  double jmax = 0, jsum = 0;
  for (const Vec3& d : probe) {
    const double j = area_element(s, d);
    jmax = std::max(jmax, j);
    jsum += j;
  }
  jmax *= 1.25;
  const double area = jsum * 4 * kPi / probe.size();  // the surface's area, estimated
  // Spacing at d: alpha * sqrt(area / (count * J(d))), on the sphere.
  double alpha = 0.75;
  const double cell = std::sqrt(4 * kPi / count) * 1.5;
  const int grid = static_cast<int>(std::ceil(2.0 / cell)) + 1;
  auto cell_of = [&](double x) { return std::clamp(static_cast<int>((x + 1) / cell), 0, grid - 1); };
  std::unordered_map<long long, std::vector<int>> buckets;
  auto bucket_key = [&](int i, int j, int k) { return (static_cast<long long>(i) * grid + j) * grid + k; };
  std::vector<Vec3> points;
  std::vector<double> radius;
  points.reserve(count);
  radius.reserve(count);
  Rng rng(seed);
  long tries = 0;
  while (static_cast<int>(points.size()) < count) {
    if (++tries > 40L * count) {  // saturated at this spacing: relax it
      alpha *= 0.85;
      tries = 0;
    }
    const Vec3 d = rng.direction();
    const double j = area_element(s, d);
    if (rng.uniform() * jmax > j) continue;
    const double rad = alpha * std::sqrt(area / (count * std::max(j, 1e-300)));
    const int ci = cell_of(d.x()), cj = cell_of(d.y()), ck = cell_of(d.z());
    const int reach = static_cast<int>(std::ceil(rad / cell));
    bool ok = true;
    for (int i = std::max(0, ci - reach); ok && i <= std::min(grid - 1, ci + reach); ++i)
      for (int jj = std::max(0, cj - reach); ok && jj <= std::min(grid - 1, cj + reach); ++jj)
        for (int k = std::max(0, ck - reach); ok && k <= std::min(grid - 1, ck + reach); ++k) {
          auto it = buckets.find(bucket_key(i, jj, k));
          if (it == buckets.end()) continue;
          for (int q : it->second)
            if ((points[q] - d).norm() < std::min(rad, radius[q])) {
              ok = false;
              break;
            }
        }
    if (!ok) continue;
    buckets[bucket_key(ci, cj, ck)].push_back(static_cast<int>(points.size()));
    points.push_back(d);
    radius.push_back(rad);
  }
  return points;
}

double corner_angle(const Vec3& at, const Vec3& p, const Vec3& q) {
  const Vec3 a = p - at, b = q - at;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// Orientation of a parameter triangle seen from outside the sphere (positive: counter-clockwise).
double sphere_orientation(const Vec3& a, const Vec3& b, const Vec3& c) { return a.dot(b.cross(c)); }

/// Flips edges of the parameter triangulation towards a Delaunay triangulation of the 3D surface
/// (the two angles opposite an edge summing to at most pi), as long as the flip keeps every
/// parameter triangle positively oriented. Deterministic: edges in a fixed queue order.
void delaunay_flips(std::vector<Tri>& faces, const std::vector<Vec3>& param, const std::vector<Vec3>& pos) {
  auto key = [](int a, int b) { return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b)); };
  std::unordered_map<std::uint64_t, std::array<int, 2>> edge_faces;
  edge_faces.reserve(faces.size() * 2);
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    for (int i = 0; i < 3; ++i) {
      auto [it, inserted] = edge_faces.try_emplace(key(faces[f][i], faces[f][(i + 1) % 3]), std::array<int, 2>{f, -1});
      if (!inserted) it->second[1] = f;
    }
  std::vector<std::uint64_t> queue;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    for (int i = 0; i < 3; ++i)
      if (faces[f][i] < faces[f][(i + 1) % 3]) queue.push_back(key(faces[f][i], faces[f][(i + 1) % 3]));
  std::sort(queue.begin(), queue.end());
  const long max_flips = 20L * static_cast<long>(faces.size());
  long flips = 0;
  for (std::size_t qi = 0; qi < queue.size() && flips < max_flips; ++qi) {
    const std::uint64_t e = queue[qi];
    auto it = edge_faces.find(e);
    if (it == edge_faces.end()) continue;
    const int f0 = it->second[0], f1 = it->second[1];
    const int u = static_cast<int>(e >> 32), w = static_cast<int>(e & 0xffffffffu);
    // f0 holds the directed edge a->b, f1 the edge b->a.
    auto third = [&](int f, int x, int y) {
      for (int v : faces[f])
        if (v != x && v != y) return v;
      return -1;
    };
    auto has_directed = [&](int f, int x, int y) {
      for (int i = 0; i < 3; ++i)
        if (faces[f][i] == x && faces[f][(i + 1) % 3] == y) return true;
      return false;
    };
    int a = u, b = w, g0 = f0, g1 = f1;
    if (!has_directed(g0, a, b)) std::swap(a, b);
    if (!has_directed(g0, a, b)) std::swap(g0, g1);
    if (!has_directed(g0, a, b) || !has_directed(g1, b, a)) continue;
    const int c = third(g0, a, b), d = third(g1, a, b);
    if (c == d || edge_faces.count(key(c, d))) continue;
    const double opposite = corner_angle(pos[c], pos[a], pos[b]) + corner_angle(pos[d], pos[b], pos[a]);
    if (opposite <= kPi + 1e-9) continue;
    if (sphere_orientation(param[c], param[a], param[d]) <= 1e-14 || sphere_orientation(param[d], param[b], param[c]) <= 1e-14)
      continue;
    if ((pos[a] - pos[c]).cross(pos[d] - pos[c]).norm() <= 0 || (pos[b] - pos[d]).cross(pos[c] - pos[d]).norm() <= 0)
      continue;
    faces[g0] = {c, a, d};
    faces[g1] = {d, b, c};
    edge_faces.erase(it);
    edge_faces[key(c, d)] = {g0, g1};
    for (auto [x, y, from, to] : {std::array<int, 4>{a, d, g1, g0}, std::array<int, 4>{b, c, g0, g1}}) {
      auto& slot = edge_faces[key(x, y)];
      for (int& f : slot)
        if (f == from) f = to;
    }
    ++flips;
    for (auto [x, y] : {std::pair{a, d}, std::pair{d, b}, std::pair{b, c}, std::pair{c, a}}) queue.push_back(key(x, y));
  }
}

/// The face of a parameter triangulation whose central projection contains d, and the
/// barycentric weights of the ray's crossing of its plane (brute force: landmarks are few).
landmarks::SurfacePoint locate_parameter(const std::vector<Tri>& faces, const std::vector<Vec3>& param, const Vec3& d) {
  landmarks::SurfacePoint best;
  double best_min = -1e300;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
    const Vec3 &p0 = param[faces[f][0]], &p1 = param[faces[f][1]], &p2 = param[faces[f][2]];
    if (d.dot(p0 + p1 + p2) <= 0) continue;  // the far side of the sphere
    const Vec3 b(d.dot(p1.cross(p2)), d.dot(p2.cross(p0)), d.dot(p0.cross(p1)));
    const double sum = b.sum();
    if (sum <= 0) continue;
    const Vec3 w = b / sum;
    if (w.minCoeff() > best_min) {
      best_min = w.minCoeff();
      best.face = f;
      best.bary = {w.x(), w.y(), w.z()};
    }
  }
  return best;
}

FamilyShape make_mesh(const FamilyOptions& o, const Base& base, const ShapeParams& s, int index) {
  FamilyShape shape;
  char name[32];
  std::snprintf(name, sizeof name, "shape%02d", index);
  shape.name = name;
  const int vertices = o.faces / 2 + 2;
  // A sampling too coarse for a sharp spot of the smooth surface (a thin, strongly bent limb tip at
  // a high variation) can leave a face folded against it; the parameters are then sampled again
  // with the next seed of the shape (deterministic: attempt 0 is the shape's own seed).
  std::string problem;
  for (int attempt = 0; attempt < kSamplingAttempts; ++attempt) {
    problem.clear();
    shape.parameters = sample_parameters(
        s, vertices, mix(o.seed, 5000 + static_cast<std::uint64_t>(index) + 100000 * static_cast<std::uint64_t>(attempt)));
    shape.mesh.faces = detail::sphere_hull(shape.parameters);
    shape.mesh.positions.resize(vertices);
    for (int v = 0; v < vertices; ++v) shape.mesh.positions[v] = surface_point(s, shape.parameters[v]);
    delaunay_flips(shape.mesh.faces, shape.parameters, shape.mesh.positions);

    // Own checks: an accepted mesh that faces outward, and no face folded against the smooth
    // surface (the face normal agrees with the surface normal at the face's parameter centroid).
    const mesh::ValidationResult valid = mesh::validate(shape.mesh);
    if (!valid.report.accepted || valid.report.orientation_flipped || mesh::find_problem(valid.report, "zero_area_faces")) {
      problem = "fails validation:\n" + mesh::format_report(shape.name, valid.report);
      continue;
    }
    int folded = 0;
    for (const Tri& t : shape.mesh.faces) {
      const Vec3& a = shape.mesh.positions[t[0]];
      const Vec3 n = (shape.mesh.positions[t[1]] - a).cross(shape.mesh.positions[t[2]] - a);
      const Vec3 c = (shape.parameters[t[0]] + shape.parameters[t[1]] + shape.parameters[t[2]]).normalized();
      if (n.dot(surface_normal(s, c)) <= 0) ++folded;
    }
    if (folded == 0) break;
    problem = "has " + std::to_string(folded) + " faces folded against its smooth surface";
  }
  if (!problem.empty())
    throw InvalidInput("family: generated " + shape.name + " (seed " + std::to_string(o.seed) + ", variation " +
                       std::to_string(o.variation) + ", " + std::to_string(o.faces) + " faces) " + problem + " in " +
                       std::to_string(kSamplingAttempts) +
                       " samplings: the shape is too sharp for this face count; use more faces or a lower variation");

  auto landmark = [&](const std::string& lname, const Vec3& d) {
    FamilyLandmark l;
    l.name = lname;
    l.parameter = d.normalized();
    l.where = locate_parameter(shape.mesh.faces, shape.parameters, l.parameter);
    if (l.where.face < 0) throw InternalError("family: landmark " + lname + " lies in no parameter triangle");
    return l;
  };
  // Seeds: a belt around the body's middle (top, right side, bottom, left side), slightly off the
  // symmetry planes so that no shortest path is a tie.
  const Vec3 seed_dirs[4] = {Vec3(0.03, 0.02, 1), Vec3(0.02, -1, 0.03), Vec3(-0.03, -0.02, -1), Vec3(-0.02, 1, -0.03)};
  for (int k = 0; k < 4; ++k) shape.seeds.push_back(landmark("seed" + std::to_string(k), seed_dirs[k]));
  for (const Limb& l : base.limbs_base) shape.features.push_back(landmark(l.name, l.axis));
  std::sort(shape.features.begin(), shape.features.end(),
            [](const FamilyLandmark& x, const FamilyLandmark& y) { return x.name < y.name; });
  return shape;
}

}  // namespace

Vec3 family_surface_point(const FamilyOptions& options, int index, const Vec3& d) {
  check_options(options);
  if (index < 0 || index >= options.shapes)
    throw InvalidInput("family_surface_point: shape " + std::to_string(index) + " is outside [0, " +
                       std::to_string(options.shapes) + ")");
  const Base base = make_base(options);
  return surface_point(make_shape(options, base, index), d.normalized());
}

Family generate_family(const FamilyOptions& options, const Context& context) {
  std::vector<FamilyShape> shapes;
  Family family = generate_family(options, context, [&](FamilyShape&& s) { shapes.push_back(std::move(s)); });
  family.shapes = std::move(shapes);
  return family;
}

Family generate_family(const FamilyOptions& options, const Context& context,
                       const std::function<void(FamilyShape&&)>& sink) {
  check_options(options);
  Family family;
  family.options = options;
  const Base base = make_base(options);
  family.limbs = base.limbs;
  for (const Limb& l : base.limbs_base) family.limb_names.push_back(l.name);
  const int batch = std::max(1, std::min(thread_count(0, context), options.shapes));
  std::vector<FamilyShape> shapes;
  for (int first = 0; first < options.shapes; first += batch) {
    const int count = std::min(batch, options.shapes - first);
    shapes.assign(static_cast<std::size_t>(count), FamilyShape{});
    parallel_for(count, context, [&](int k) {
      shapes[k] = make_mesh(options, base, make_shape(options, base, first + k), first + k);
    });
    for (auto& shape : shapes) sink(std::move(shape));
    context.report("family", static_cast<double>(first + count) / options.shapes);
  }
  return family;
}

std::string landmarks_json(const FamilyShape& shape) {
  auto num = [](double x) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", x);
    return std::string(buf);
  };
  auto ref = [&](const FamilyLandmark& l) {
    return "{\"face\": " + std::to_string(l.where.face) + ", \"bary\": [" + num(l.where.bary[0]) + ", " +
           num(l.where.bary[1]) + ", " + num(l.where.bary[2]) + "]}";
  };
  std::ostringstream s;
  s << "{\n  \"seeds\": [\n";
  for (std::size_t i = 0; i < shape.seeds.size(); ++i)
    s << "    " << ref(shape.seeds[i]) << (i + 1 < shape.seeds.size() ? ",\n" : "\n");
  s << "  ],\n  \"features\": {\n";
  for (std::size_t i = 0; i < shape.features.size(); ++i)
    s << "    \"" << shape.features[i].name << "\": " << ref(shape.features[i])
      << (i + 1 < shape.features.size() ? ",\n" : "\n");
  s << "  }\n}\n";
  return s.str();
}

}  // namespace qs::family
