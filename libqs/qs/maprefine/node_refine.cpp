// The node refiner and the untangler that the dissection calls before it splits a node
// (DissectOptions::refine_before_split, DissectOptions::same_pose_untangle).
#include "qs/maprefine/map_refine_detail.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "qs/core/error.h"
#include "qs/param/square_param.h"

namespace qs::maprefine {

using namespace detail;

namespace {

using detail::jacobian_matrix;

// The reference patch of refine_patch as it is: its uv triangles located exactly (a uniform grid
// over the unit square, about one cell per face), and the 3D point and Jacobian at any uv.
class ExactReference {
 public:
  ExactReference(const param::PatchMesh& ref, const std::vector<Vec2>& uv) : ref_(ref) {
    const size_t nf = ref.faces.size();
    jacobian_.assign(nf, Mat32::Zero());
    std::vector<char> positive(nf, 0);
    for (size_t f = 0; f < nf; ++f) {
      const auto& t = ref.faces[f];
      Mat32 e;
      e.col(0) = ref.positions[t[1]] - ref.positions[t[0]];
      e.col(1) = ref.positions[t[2]] - ref.positions[t[0]];
      Eigen::Matrix2d ds;
      ds.col(0) = uv[t[1]] - uv[t[0]];
      ds.col(1) = uv[t[2]] - uv[t[0]];
      area_ += 0.5 * e.col(0).cross(e.col(1)).norm();
      const double auv = 0.5 * ds.determinant();
      if (!(auv > param::kZeroUvArea)) continue;
      const Mat32 g = e * ds.inverse();
      jacobian_[f] = g;
      positive[f] = 1;
    }
    std::vector<std::array<Vec2, 3>> tris(nf);
    for (size_t f = 0; f < nf; ++f) tris[f] = {uv[ref.faces[f][0]], uv[ref.faces[f][1]], uv[ref.faces[f][2]]};
    locator_.emplace(std::move(tris), positive, true);
  }

  double area() const { return area_; }

  // The face holding q (clamped to the square; the face where q is least outside when it lies in
  // none, e.g. by rounding on an edge) and q's barycentric coordinates in it, clamped to the
  // face; -1 when the patch has no positive uv face. `hint`: a face to try first, updated.
  int locate(const Vec2& q_in, int& hint, Vec3& bary) const {
    return locator_->locate(q_in.cwiseMax(0.0).cwiseMin(1.0), hint, bary);
  }

  // The reference's 3D point at q (linear in the face holding q); false when there is none.
  bool point(const Vec2& q, int& hint, Vec3& x) const {
    Vec3 b;
    const int f = locate(q, hint, b);
    if (f < 0) return false;
    const auto& t = ref_.faces[f];
    x = b[0] * ref_.positions[t[0]] + b[1] * ref_.positions[t[1]] + b[2] * ref_.positions[t[2]];
    return true;
  }

  // point(), and d point / d uv there (the Jacobian of the face holding q).
  bool point(const Vec2& q, int& hint, Vec3& x, Mat32& jacobian) const {
    if (!point(q, hint, x)) return false;
    jacobian = jacobian_[hint];
    return true;
  }

 private:
  const param::PatchMesh& ref_;
  std::vector<Mat32> jacobian_;
  double area_ = 0;
  std::optional<UvLocator> locator_;
};

// vec(J) = a x for J = [Q1 x1 - Q0 x0, Q2 x2 - Q0 x0] P (jacobian_matrix with one Q per corner).
Mat46 jacobian_matrix(const std::array<Eigen::Matrix2d, 3>& q, const Eigen::Matrix2d& p) {
  Mat46 a = Mat46::Zero();
  for (int r = 0; r < 2; ++r)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c)
        for (int d = 0; d < 2; ++d) {
          a(2 * r + b, 2 * (d + 1) + c) += q[d + 1](r, c) * p(d, b);
          a(2 * r + b, c) -= q[0](r, c) * p(d, b);
        }
  return a;
}

// The composition for a one-patch problem: per face t of B, the composed map B -> uv -> A
// on t is B's triangle onto the triangle of A's points at t's three uv corners (located exactly in
// A's uv triangles). Its Jacobian, in an orthonormal frame R of that image triangle, linearized at
// the current uv with each corner moving along the A face that holds it (x_k + G_k du_k):
// J = sqrt(s) R^T [x1 - x0, x2 - x0] P, exact at the current uv and in its first derivative, so
// that the solver's fixed points are stationary points of the composition's own energy (a metric
// frozen at the current uv is not: its change with the position is left out of the gradient).
// s = area_B / area_A of the patch.
LinearizeFn composition_linearization(const PatchProblem& prob, const ExactReference& ref, double scale) {
  auto hints = std::make_shared<std::vector<int>>(3 * prob.faces.size(), -1);
  const double root = std::sqrt(scale);
  return [&prob, &ref, root, hints](size_t t, Mat46& a, Eigen::Vector4d& b) {
    const auto& c = prob.tri[t];
    const Eigen::Matrix2d& p = prob.dm_inv[t];
    Vec3 x[3];
    Mat32 g[3];
    for (int k = 0; k < 3; ++k)
      if (!ref.point(prob.uv[c[k]], (*hints)[3 * t + k], x[k], g[k])) {  // no positive face at all
        a = jacobian_matrix(root * Eigen::Matrix2d::Identity(), p);
        b.setZero();
        return;
      }
    Mat32 e;
    e.col(0) = x[1] - x[0];
    e.col(1) = x[2] - x[0];
    // The frame: the image triangle's plane, oriented as it (else the plane of corner 0's face).
    Vec3 n = e.col(0).cross(e.col(1));
    Vec3 r1 = e.col(0).norm() > 0 ? Vec3(e.col(0)) : Vec3(e.col(1));
    if (!(n.norm() > 1e-14 * e.col(0).norm() * e.col(1).norm()) || !(r1.norm() > 0)) {
      n = g[0].col(0).cross(g[0].col(1));
      r1 = g[0].col(0);
    }
    r1.normalize();
    const Vec3 r2 = n.cross(r1).normalized();
    Mat32 r;
    r.col(0) = r1;
    r.col(1) = r2;
    std::array<Eigen::Matrix2d, 3> q;
    for (int k = 0; k < 3; ++k) q[k] = root * r.transpose() * g[k];
    a = jacobian_matrix(q, p);
    const Eigen::Matrix2d j = root * r.transpose() * e * p;
    Vec6 u;
    u << prob.uv[c[0]], prob.uv[c[1]], prob.uv[c[2]];
    b = Eigen::Vector4d(j(0, 0), j(0, 1), j(1, 0), j(1, 1)) - a * u;
  };
}

// refine_patch's and pull_patch's checks (`who` names the caller) and the patch as a problem: every
// vertex its own wedge; boundary loop, held and unused ones fixed. None: nothing to solve.
std::optional<PatchProblem> node_problem(const char* who, const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv,
                                         const param::PatchMesh& patch, const std::vector<Vec2>& uv,
                                         const std::vector<char>& held, const RefineOptions& options) {
  if (ref_uv.size() != ref.positions.size() || uv.size() != patch.positions.size() ||
      held.size() != patch.positions.size())
    throw InvalidInput(std::string(who) + ": the reference patch has " + std::to_string(ref.positions.size()) +
                       " vertices and " + std::to_string(ref_uv.size()) + " uv, the patch " +
                       std::to_string(patch.positions.size()) + " vertices, " + std::to_string(uv.size()) + " uv and " +
                       std::to_string(held.size()) + " held flags; expected equal counts");
  if (options.iterations < 0 || !(options.tolerance >= 0))
    throw InvalidInput(std::string(who) + ": iterations (" + std::to_string(options.iterations) + ") and tolerance (" +
                       std::to_string(options.tolerance) + ") must be >= 0");
  if (ref.faces.empty() || patch.faces.empty() || options.iterations == 0) return std::nullopt;
  for (const auto& t : ref.faces)
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(ref.positions.size()))
        throw InvalidInput(std::string(who) + ": a face of the reference uses vertex " + std::to_string(v) +
                           ", expected 0.." + std::to_string(ref.positions.size() - 1));
  // The patch as a problem: every vertex its own wedge; boundary loop, held and unused ones fixed.
  const size_t nv = patch.positions.size();
  std::vector<char> fixed(nv, 1);
  for (const auto& t : patch.faces)
    for (int v : t)
      if (v < 0 || v >= static_cast<int>(nv))
        throw InvalidInput(std::string(who) + ": a face uses vertex " + std::to_string(v) + ", expected 0.." +
                           std::to_string(nv - 1));
      else
        fixed[v] = held[v] != 0;
  for (int v : patch.boundary)
    if (v >= 0 && v < static_cast<int>(nv)) fixed[v] = 1;
  PatchProblem pr;
  pr.vertices.resize(nv);
  pr.uv = uv;
  pr.var.assign(nv, -1);
  pr.dims.assign(nv, 0);
  pr.basis.assign(nv, Vec2::Zero());
  for (size_t v = 0; v < nv; ++v) {
    pr.vertices[v] = static_cast<int>(v);
    if (!fixed[v]) {
      pr.var[v] = pr.unknowns;
      pr.dims[v] = 2;
      pr.unknowns += 2;
    }
  }
  for (size_t f = 0; f < patch.faces.size(); ++f) {
    const auto& t = patch.faces[f];
    pr.faces.push_back(static_cast<int>(f));
    pr.face_patch.push_back(0);
    pr.tri.push_back({t[0], t[1], t[2]});
    double area = 0;
    const Eigen::Matrix2d dm = local_edges(patch.positions[t[0]], patch.positions[t[1]], patch.positions[t[2]], area);
    pr.dm_inv.push_back(dm.inverse());
    pr.area.push_back(area);
    pr.total_area += area;
  }
  if (pr.unknowns == 0) return std::nullopt;
  return pr;
}

}  // namespace

bool refine_patch(const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv, const param::PatchMesh& patch,
                  std::vector<Vec2>& uv, const std::vector<char>& held, const RefineOptions& options,
                  const NodeRefineOptions& node) {
  if (!(node.tolerance >= 0))
    throw InvalidInput("refine_patch: node tolerance " + std::to_string(node.tolerance) +
                       " must be >= 0 (0: RefineOptions::tolerance)");
  if (!(node.max_start_distortion >= 0))
    throw InvalidInput("refine_patch: max_start_distortion (" + std::to_string(node.max_start_distortion) +
                       ") must be >= 0 (0: no limit)");
  auto problem = node_problem("refine_patch", ref, ref_uv, patch, uv, held, options);
  if (!problem) return false;
  PatchProblem& pr = *problem;
  const ExactReference exact(ref, ref_uv);
  const double scale = exact.area() > 0 ? pr.total_area / exact.area() : 1.0;
  const LinearizeFn linearize = composition_linearization(pr, exact, scale);
  const MetricFn unused = [](size_t, const Vec2&) { return Eigen::Matrix2d(Eigen::Matrix2d::Identity()); };
  RefineOptions node_options = options;
  if (node.tolerance > 0) node_options.tolerance = node.tolerance;
  const PatchResult r =
      solve_problem(pr, unused, node_options, true, Vec2(1, 1), Vec2(0, 0), &linearize, node.max_start_distortion);
  if (!r.changed) return false;
  uv = pr.uv;
  return true;
}

dissect::NodeMapRefiner node_refiner(const RefineOptions& options, const NodeRefineOptions& node) {
  return [options, node](const param::PatchMesh& ref, const std::vector<Vec2>& ref_uv, const param::PatchMesh& patch,
                         std::vector<Vec2>& uv, const std::vector<char>& held) {
    return refine_patch(ref, ref_uv, patch, uv, held, options, node);
  };
}

bool untangle_patch(const param::PatchMesh& patch, std::vector<Vec2>& uv, const std::vector<char>& held,
                    const std::vector<Vec2>& target, const std::vector<char>& has_target, double pull,
                    const RefineOptions& options) {
  const size_t n = patch.positions.size();
  if (uv.size() != n || held.size() != n || target.size() != n || has_target.size() != n)
    throw InvalidInput("untangle_patch: the patch has " + std::to_string(n) + " vertices, " +
                       std::to_string(uv.size()) + " uv, " + std::to_string(held.size()) + " held flags, " +
                       std::to_string(target.size()) + " targets and " + std::to_string(has_target.size()) +
                       " target flags; expected equal counts");
  if (!(pull >= 0 && std::isfinite(pull)))
    throw InvalidInput("untangle_patch: pull " + std::to_string(pull) + " must be finite and >= 0");
  // The patch is its own reference: node_problem's checks, with `patch` in both roles.
  auto problem = node_problem("untangle_patch", patch, uv, patch, uv, held, options);
  if (!problem) return false;
  PatchProblem& pr = *problem;
  // Each face's frame is its start (u, v) triangle instead of its 3D triangle, so the distortion
  // is 4 per unit area at the start however squeezed the map is on the surface (measured against
  // the 3D triangles or the first mesh's map, a squeezed node starts at 10^5..10^6 and the pull
  // moves nothing); the pull's weight per vertex is a third of its faces' start uv area.
  // Faces without a free vertex add a constant: left out (a local untangle solves only its region).
  {
    size_t kept = 0;
    for (size_t t = 0; t < pr.tri.size(); ++t) {
      const auto& c = pr.tri[t];
      if (pr.dims[c[0]] == 0 && pr.dims[c[1]] == 0 && pr.dims[c[2]] == 0) continue;
      pr.faces[kept] = pr.faces[t];
      pr.face_patch[kept] = pr.face_patch[t];
      pr.tri[kept] = pr.tri[t];
      pr.dm_inv[kept] = pr.dm_inv[t];
      pr.area[kept] = pr.area[t];
      ++kept;
    }
    pr.faces.resize(kept);
    pr.face_patch.resize(kept);
    pr.tri.resize(kept);
    pr.dm_inv.resize(kept);
    pr.area.resize(kept);
  }
  std::vector<double> area(pr.uv.size(), 0.0);
  pr.total_area = 0;
  for (size_t t = 0; t < pr.tri.size(); ++t) {
    const auto& c = pr.tri[t];
    Eigen::Matrix2d e;
    e.col(0) = pr.uv[c[1]] - pr.uv[c[0]];
    e.col(1) = pr.uv[c[2]] - pr.uv[c[0]];
    const double a = 0.5 * e.determinant();
    if (!(a > param::kZeroUvArea)) return false;  // not a bijective start
    pr.dm_inv[t] = e.inverse();
    pr.area[t] = a;
    pr.total_area += a;
    for (int l : c) area[l] += a / 3;
  }
  pr.pull.assign(pr.uv.size(), Eigen::Matrix2d::Zero());
  pr.target.assign(pr.uv.size(), Vec2::Zero());
  for (size_t v = 0; v < pr.uv.size(); ++v)
    if (pr.dims[v] > 0 && has_target[v]) {
      pr.target[v] = target[v];
      pr.pull[v] = pull * area[v] * Eigen::Matrix2d::Identity();
    }
  const MetricFn identity = [](size_t, const Vec2&) { return Eigen::Matrix2d(Eigen::Matrix2d::Identity()); };
  if (!solve_problem(pr, identity, options, true).changed) return false;
  uv = pr.uv;
  return true;
}

dissect::NodeMapPuller untangler(const RefineOptions& options, double pull) {
  return [options, pull](const param::PatchMesh& patch, std::vector<Vec2>& uv, const std::vector<char>& held,
                         const std::vector<Vec2>& target, const std::vector<char>& has_target, bool polish) {
    RefineOptions o = options;
    if (polish) o.iterations = std::min(o.iterations, kPolishIterations);
    return untangle_patch(patch, uv, held, target, has_target, pull, o);
  };
}

}  // namespace qs::maprefine
