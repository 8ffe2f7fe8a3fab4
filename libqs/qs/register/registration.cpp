#include "qs/register/registration.h"

#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "qs/core/anderson.h"
#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/landmarks/landmarks.h"
#include "qs/mesh/simplify.h"
#include "qs/metro/metro.h"
#include "qs/param/sparse_cholesky.h"

namespace qs::registration {
namespace {

/// Vertices per task of the parallel passes.
constexpr int kBlock = 1024;

/// Steps of extract_rotation per round.
constexpr int kRotationSteps = 6;

/// Past rounds that the Anderson acceleration combines.
constexpr int kAndersonDepth = 5;

/// A facing nearest point keeps a thin part's sides apart (two fingers, a lip); its normal may
/// be turned this far from the query's (cos).
constexpr double kFacingCos = 0.3;

/// The stages whose pull weight is at least this also pull A toward B's points (the cover): in
/// the weaker stages the limbs bend as rigid parts and the cover would not change them.
constexpr double kCoverFrom = 1e-2;

/// B's points that pull A's nearest points (the pull the other way): with the pull toward B
/// alone, A may slide off a protruding part of B (a muzzle, a fingertip) and leave it uncovered.
struct Cover {
  std::vector<Vec3> point, normal;
  std::vector<double> area;  ///< each point's share of B's area, in all 1
  explicit Cover(const TriMesh& b) : point(b.positions), normal(vertex_normals(b.positions, b.faces)) {
    area.assign(point.size(), 0.0);
    double total = 0;
    for (const Tri& t : b.faces) {
      const double ar = 0.5 * (point[t[1]] - point[t[0]]).cross(point[t[2]] - point[t[0]]).norm();
      for (int v : t) area[v] += ar / 3;
      total += ar;
    }
    for (double& ar : area) ar /= total;
  }
};

template <class F>
void for_blocks(int n, int threads, const Context& context, F&& body) {
  parallel_for((n + kBlock - 1) / kBlock, threads, context, [&](int b) {
    const int end = std::min(n, (b + 1) * kBlock);
    for (int i = b * kBlock; i < end; ++i) body(i);
  });
}

/// The rotation part of a (the rotation R maximizing trace(R^T a)), improved from q in place
/// (Mueller, Bender, Chentanez and Macklin 2016: a robust method to extract the rotational part
/// of deformations; warm-started from the last round's, a few steps suffice).
void extract_rotation(const Eigen::Matrix3d& a, Eigen::Quaterniond& q) {
  for (int step = 0; step < kRotationSteps; ++step) {
    const Eigen::Matrix3d r = q.toRotationMatrix();
    const Vec3 omega = (r.col(0).cross(a.col(0)) + r.col(1).cross(a.col(1)) + r.col(2).cross(a.col(2))) /
                       (std::abs(r.col(0).dot(a.col(0)) + r.col(1).dot(a.col(1)) + r.col(2).dot(a.col(2))) + 1e-12);
    const double angle = omega.norm();
    if (angle < 1e-12) break;
    q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, omega / angle)) * q;
    q.normalize();
  }
}

/// The point of `mesh` nearest to x, as a face and barycentric weights.
struct Located {
  int face = -1;
  std::array<double, 3> w{};
};
Located locate(const TriMesh& mesh, const metro::SurfaceDistance& tree, const Vec3& x) {
  const auto c = tree.closest(x);
  if (c.face < 0) return {};
  const Tri& t = mesh.faces[c.face];
  return {c.face, landmarks::closest_on_triangle(x, mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]])};
}

/// The weights of the point of triangle t (corners in p) nearest to x.
std::array<double, 3> closest_weights(const Tri& t, const Vec3& x, const std::vector<Vec3>& p) {
  return landmarks::closest_on_triangle(x, p[t[0]], p[t[1]], p[t[2]]);
}

/// The vertex of a located point's face with the largest weight.
int nearest_corner(const TriMesh& mesh, const Located& l) {
  const int k = l.w[0] >= l.w[1] ? (l.w[0] >= l.w[2] ? 0 : 2) : (l.w[1] >= l.w[2] ? 1 : 2);
  return mesh.faces[l.face][k];
}

/// The as-rigid-as-possible deformation of one tessellation of A (rest: in B's frame) toward B,
/// its landmarks held: cotangent weights, the held points, and the state that the stages move.
class Deformation {
 public:
  /// `original`: the tessellation in A's frame (where the landmarks are located); `rest`: the same
  /// moved by the landmarks' similarity.
  Deformation(const TriMesh& original, std::vector<Vec3> rest, const std::vector<LandmarkPair>& landmarks,
              int threads, const Context& context)
      : faces_(original.faces), rest_(std::move(rest)), n_(original.num_vertices()), threads_(threads),
        context_(context) {
    const int n = n_;
    // Cotangent weights of the rest shape, per vertex's neighbours (CSR; an edge once per face).
    start_.assign(n + 1, 0);
    for (const Tri& t : faces_)
      for (int v : t) start_[v + 1] += 2;
    for (int i = 0; i < n; ++i) start_[i + 1] += start_[i];
    nbr_.resize(start_[n]);
    weight_.resize(start_[n]);
    area_.assign(n, 0.0);
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    for (const Tri& t : faces_) {
      for (int c = 0; c < 3; ++c) {
        const int i = t[c], j = t[(c + 1) % 3], k = t[(c + 2) % 3];
        const Vec3 u = rest_[i] - rest_[k], v = rest_[j] - rest_[k];
        const double cross = u.cross(v).norm();
        const double w = 0.5 * std::clamp(cross > 0 ? u.dot(v) / cross : 0.0, 1e-3, 1e3);
        nbr_[fill[i]] = j;
        weight_[fill[i]++] = w;
        nbr_[fill[j]] = i;
        weight_[fill[j]++] = w;
      }
      const double ar = 0.5 * (rest_[t[1]] - rest_[t[0]]).cross(rest_[t[2]] - rest_[t[0]]).norm();
      for (int v : t) area_[v] += ar / 3;
    }
    for (int i = 0; i < n; ++i) {
      mean_area_ += area_[i] / n;
      for (int p = start_[i]; p < start_[i + 1]; ++p) mean_weight_ += weight_[p] / n;
    }
    // The landmarks held at B's points: A's point of each, as a face and weights.
    const metro::SurfaceDistance on_a(original, "A", thread_count(threads_, context_));
    for (const LandmarkPair& l : landmarks) {
      const Located at = locate(original, on_a, l.on_a);
      if (at.face >= 0) held_.push_back({faces_[at.face], at.w, l.on_b});
    }
    hold_ = 1e3 * mean_weight_;
    x_ = rest_;
    rot_.assign(n, Eigen::Matrix3d::Identity());
    quat_.assign(n, Eigen::Quaterniond::Identity());
    target_.resize(n);
    hint_.assign(n, -1);
    vertex_energy_.resize(n);
  }

  const std::vector<Vec3>& rest() const { return rest_; }
  std::vector<Vec3>& positions() { return x_; }
  std::vector<Eigen::Quaterniond>& rotations() { return quat_; }
  const std::vector<Eigen::Matrix3d>& rotation_matrices() const { return rot_; }

  /// One stage: pull weight mu, `iterations` local/global rounds from the current positions. Each
  /// vertex is pulled toward its nearest point of B (on_b) and, given a cover, toward the cover's
  /// points whose nearest points of A lie on its faces, the two targets weighed by area.
  void stage(double mu, int iterations, const metro::SurfaceDistance& on_b, const Cover* cover) {
    const int n = n_;
    double total_area = 0;
    for (double ar : area_) total_area += ar;
    // Each cover point's nearest point of the moving A (face -1: none facing), found again each
    // round (keeping them for a few rounds measured worse).
    std::vector<Located> found(cover ? cover->point.size() : 0);
    std::vector<Vec3> shift(n);
    std::vector<double> share(n);
    // The system of this stage: rigidity + pull + holds (lower triangle).
    std::vector<Eigen::Triplet<double>> lower;
    lower.reserve(start_[n] + n + 9 * held_.size());
    for (int i = 0; i < n; ++i) {
      double diag = mu * mean_weight_ * area_[i] / mean_area_;
      for (int p = start_[i]; p < start_[i + 1]; ++p) {
        diag += weight_[p];
        if (nbr_[p] < i) lower.emplace_back(i, nbr_[p], -weight_[p]);  // row nbr[p] holds the same weight
      }
      lower.emplace_back(i, i, diag);
    }
    for (const Held& h : held_)
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          if (h.t[r] >= h.t[c]) lower.emplace_back(h.t[r], h.t[c], hold_ * h.w[r] * h.w[c]);
    Eigen::SparseMatrix<double> m(n, n);
    m.setFromTriplets(lower.begin(), lower.end());
    m.makeCompressed();
    if (!analyzed_) {
      llt_.analyze(m);
      analyzed_ = true;
    }
    if (!llt_.factorize(m, threads_))
      throw InternalError("register_surface: the deformation's system is not positive definite");
    const double pull = mu * mean_weight_ / mean_area_;
    auto& x = x_;
    // Local step at x: each vertex's rotation, its pull's target, and the energy that the
    // global step lowers (with these rotations and targets).
    auto local = [&]() {
      if (cover) {
        const TriMesh moving{x, faces_};
        if (on_x_) on_x_->refit(moving);
        else on_x_.emplace(moving, "the registered A", thread_count(threads_, context_));
        cover_hint_.resize(found.size(), -1);
        for_blocks(static_cast<int>(found.size()), threads_, context_, [&](int j) {
          const auto c = on_x_->closest_facing(cover->point[j], cover->normal[j], kFacingCos, cover_hint_[j]);
          found[j] = c.face < 0 ? Located{} : Located{c.face, closest_weights(faces_[c.face], cover->point[j], x)};
        });
      }
      std::fill(shift.begin(), shift.end(), Vec3::Zero());
      std::fill(share.begin(), share.end(), 0.0);
      for (size_t j = 0; j < found.size(); ++j) {
        if (found[j].face < 0) continue;
        const Tri& t = faces_[found[j].face];
        const auto& w = found[j].w;
        const Vec3 at = w[0] * x[t[0]] + w[1] * x[t[1]] + w[2] * x[t[2]];
        const double ar = cover->area[j] * total_area;
        for (int r = 0; r < 3; ++r) {
          shift[t[r]] += ar * w[r] * (cover->point[j] - at);
          share[t[r]] += ar * w[r];
        }
      }
      const std::vector<Vec3> normal = vertex_normals(x, faces_);
      for_blocks(n, threads_, context_, [&](int i) {
        Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
        for (int p = start_[i]; p < start_[i + 1]; ++p)
          cov += weight_[p] * (x[i] - x[nbr_[p]]) * (rest_[i] - rest_[nbr_[p]]).transpose();
        extract_rotation(cov, quat_[i]);
        rot_[i] = quat_[i].toRotationMatrix();
        auto c = on_b.closest_facing(x[i], normal[i], kFacingCos, hint_[i]);
        if (c.face < 0) c = on_b.closest(x[i]);
        target_[i] = c.point;
        if (share[i] > 0) {  // the cover's target, weighing at most as much as the nearest point's
          const double w = std::min(share[i], area_[i]);
          target_[i] = (area_[i] * target_[i] + w * (x[i] + shift[i] / share[i])) / (area_[i] + w);
        }
        double e = 2 * pull * area_[i] * (x[i] - target_[i]).squaredNorm();
        for (int p = start_[i]; p < start_[i + 1]; ++p)
          e += weight_[p] * ((x[i] - x[nbr_[p]]) - rot_[i] * (rest_[i] - rest_[nbr_[p]])).squaredNorm();
        vertex_energy_[i] = e;
      });
      double e = 0;
      for (int i = 0; i < n; ++i) e += vertex_energy_[i];
      for (const Held& h : held_)
        e += 2 * hold_ * (h.w[0] * x[h.t[0]] + h.w[1] * x[h.t[1]] + h.w[2] * x[h.t[2]] - h.target).squaredNorm();
      return e;
    };
    // Global step: the positions that the rotations and targets ask for.
    auto global = [&]() {
      Eigen::MatrixXd rhs(n, 3);
      for_blocks(n, threads_, context_, [&](int i) {
        Vec3 r = pull * area_[i] * target_[i];
        for (int p = start_[i]; p < start_[i + 1]; ++p)
          r += 0.5 * weight_[p] * (rot_[i] + rot_[nbr_[p]]) * (rest_[i] - rest_[nbr_[p]]);
        rhs.row(i) = r.transpose();
      });
      for (const Held& h : held_)
        for (int r = 0; r < 3; ++r) rhs.row(h.t[r]) += hold_ * h.w[r] * h.target.transpose();
      return Eigen::MatrixXd(llt_.solve(rhs, threads_));
    };
    // x as one vector of 3n coordinates (std::vector<Vec3> is contiguous).
    auto flat = [&]() { return Eigen::Map<Eigen::VectorXd>(x[0].data(), 3 * n); };
    // Local/global rounds, Anderson-accelerated with its safeguard: an accelerated point whose
    // energy is not below the last round's is replaced by the plain step's.
    Anderson aa(kAndersonDepth);
    double last_energy = std::numeric_limits<double>::infinity();
    bool accelerated = false;
    Eigen::VectorXd plain(3 * n);  // the last global step's positions
    for (int it = 0; it < iterations; ++it) {
      context_.check_cancel();
      double energy = local();
      if (accelerated && energy >= last_energy) {
        flat() = plain;
        energy = local();
        aa.clear();
      }
      last_energy = energy;
      const Eigen::MatrixXd sol = global();
      for (int i = 0; i < n; ++i) plain.segment<3>(3 * i) = sol.row(i).transpose();
      accelerated = aa.step(plain, plain - flat());
      flat() = accelerated ? aa.next() : plain;
    }
    flat() = plain;
  }

 private:
  struct Held {
    Tri t;
    std::array<double, 3> w;
    Vec3 target;
  };
  const std::vector<Tri>& faces_;
  std::vector<Vec3> rest_;
  int n_;
  int threads_;
  const Context& context_;
  std::vector<int> start_, nbr_;
  std::vector<double> weight_, area_;
  double mean_area_ = 0, mean_weight_ = 0, hold_ = 0;
  std::vector<Held> held_;
  std::vector<Vec3> x_, target_;
  std::vector<Eigen::Matrix3d> rot_;
  std::vector<Eigen::Quaterniond> quat_;
  std::vector<int> hint_;
  std::vector<double> vertex_energy_;
  /// The moving A's tree, refit every round of a stage with a cover, and each cover point's hint.
  std::optional<metro::SurfaceDistance> on_x_;
  std::vector<int> cover_hint_;
  param::SupernodalCholesky llt_;
  bool analyzed_ = false;
};

/// Moves the vertices of `fine` as the deformation of `coarse` (another tessellation of the same
/// surface in the same rest frame) moved the surface: each fine vertex by its nearest point of
/// the coarse rest shape, carried with that face's corners, plus its offset from there turned by
/// the nearest corner's rotation; the rotations are taken over likewise.
void carry(Deformation& coarse, const TriMesh& coarse_rest, Deformation& fine) {
  const metro::SurfaceDistance tree(coarse_rest, "the coarse A");
  const std::vector<Vec3>& rest = fine.rest();
  std::vector<Vec3>& x = fine.positions();
  std::vector<Eigen::Quaterniond>& quat = fine.rotations();
  const std::vector<Vec3>& cx = coarse.positions();
  const std::vector<Eigen::Quaterniond>& cq = coarse.rotations();
  for (size_t i = 0; i < rest.size(); ++i) {
    const Located l = locate(coarse_rest, tree, rest[i]);
    const Tri& t = coarse_rest.faces[l.face];
    const Vec3 on = l.w[0] * coarse_rest.positions[t[0]] + l.w[1] * coarse_rest.positions[t[1]] +
                    l.w[2] * coarse_rest.positions[t[2]];
    quat[i] = cq[nearest_corner(coarse_rest, l)];
    x[i] = l.w[0] * cx[t[0]] + l.w[1] * cx[t[1]] + l.w[2] * cx[t[2]] + quat[i] * (rest[i] - on);
  }
}

}  // namespace

Registration register_surface(const TriMesh& a, const TriMesh& b, const std::vector<LandmarkPair>& landmarks,
                              const RegisterOptions& options, const Context& context) {
  if (landmarks.size() < 3)
    throw InvalidInput("register_surface: " + std::to_string(landmarks.size()) +
                       " landmarks; a registration needs at least 3");
  if (options.iterations < 1 || options.stages.empty())
    throw InvalidInput("register_surface: at least one stage of at least one iteration expected");
  const int n = a.num_vertices();

  // A moved onto B by the landmarks' similarity: the rest shape.
  std::vector<Vec3> from, to;
  for (const LandmarkPair& l : landmarks) {
    from.push_back(l.on_a);
    to.push_back(l.on_b);
  }
  const Eigen::Matrix4d similarity = fit_similarity(from, to);
  const Eigen::Matrix3d linear = similarity.topLeftCorner<3, 3>();
  const double scale = std::cbrt(linear.determinant());
  const Eigen::Matrix3d turn0 = linear / scale;
  auto moved_by_similarity = [&](const std::vector<Vec3>& p) {
    std::vector<Vec3> out(p.size());
    for (size_t i = 0; i < p.size(); ++i) out[i] = (similarity * p[i].homogeneous()).head<3>();
    return out;
  };

  const int threads = thread_count(options.threads, context);
  const metro::SurfaceDistance on_b(b, "B", threads);
  // A large B: every stage but the last two pulls toward a coarser tessellation of B (the early
  // stages only bend the limbs into place; the nearest points on the fine B cost more).
  const bool coarse_b = options.coarse_faces > 0 && b.num_faces() > 2 * options.coarse_faces;
  const TriMesh b_coarse = coarse_b ? mesh::simplify(b, options.coarse_faces) : TriMesh{};
  const std::optional<metro::SurfaceDistance> on_coarse_b =
      coarse_b ? std::optional<metro::SurfaceDistance>(std::in_place, b_coarse, "B", threads) : std::nullopt;
  const Cover cover(coarse_b ? b_coarse : b);
  auto cover_in = [&](size_t stage) { return options.stages[stage] >= kCoverFrom ? &cover : nullptr; };
  auto pull_toward = [&](size_t stage) -> const metro::SurfaceDistance& {
    return on_coarse_b && stage + 2 < options.stages.size() ? *on_coarse_b : on_b;
  };
  Deformation fine(a, moved_by_similarity(a.positions), landmarks, options.threads, context);
  const std::vector<Vec3>& rest = fine.rest();
  // A large A: every stage but the last on a coarser tessellation of A, carried over to A for the
  // last, which keeps the shape that the cover settled without the cover. The pull's weight
  // against the rigidity grows with the vertex count (it is per unit area over the mean vertex
  // area), so the coarse stages' weights are scaled by the count's ratio.
  size_t first_fine = 0;
  int last_iterations = options.iterations;
  if (options.coarse_faces > 0 && a.num_faces() > 2 * options.coarse_faces && options.stages.size() > 1) {
    const TriMesh coarse_a = mesh::simplify(a, options.coarse_faces);
    Deformation coarse(coarse_a, moved_by_similarity(coarse_a.positions), landmarks, options.threads, context);
    const double ratio = static_cast<double>(n) / coarse_a.num_vertices();
    first_fine = options.stages.size() - 1;
    for (size_t s = 0; s < first_fine; ++s)
      coarse.stage(options.stages[s] * ratio, options.iterations, pull_toward(s), cover_in(s));
    carry(coarse, TriMesh{coarse.rest(), coarse_a.faces}, fine);
    last_iterations = (options.iterations + 1) / 2;
  }
  for (size_t s = first_fine; s < options.stages.size(); ++s)
    fine.stage(options.stages[s], s + 1 == options.stages.size() ? last_iterations : options.iterations,
               pull_toward(s), first_fine > 0 ? nullptr : cover_in(s));
  const std::vector<Vec3>& x = fine.positions();
  const std::vector<Eigen::Matrix3d>& rot = fine.rotation_matrices();

  for (const Vec3& p : x)
    if (!p.allFinite()) throw InternalError("register_surface: the deformation diverged (a position is not finite)");
  Registration out;
  out.positions = x;
  out.turn.resize(n);
  for (int i = 0; i < n; ++i) out.turn[i] = rot[i] * turn0;
  // Fit: both ways.
  const TriMesh moved{x, a.faces};
  const metro::SurfaceDistance on_moved(moved, "the registered A", threads);
  Context measure = context.without_progress();
  if (options.threads > 0) measure.threads = options.threads;
  const metro::VertexDistance fit = metro::vertex_distance(moved, on_moved, b, on_b, 0.99, measure);
  const double diag = bounding_box(b.positions).diagonal();
  out.mean_distance = diag > 0 ? fit.mean / diag : 0;
  out.p99_distance = diag > 0 ? fit.quantile / diag : 0;
  // Distortion: symmetric Dirichlet of each face of the rest shape onto its registered face.
  double energy = 0, energy_area = 0;
  for (const Tri& t : a.faces) {
    const Vec3 e1 = rest[t[1]] - rest[t[0]], e2 = rest[t[2]] - rest[t[0]];
    const Vec3 f1 = x[t[1]] - x[t[0]], f2 = x[t[2]] - x[t[0]];
    const double ar = 0.5 * e1.cross(e2).norm();
    if (!(ar > 0)) continue;
    // Each face in its own plane: 2x2 edge matrices.
    const Vec3 u = e1.normalized(), v = (e1.cross(e2)).cross(e1).normalized();
    Eigen::Matrix2d ea, eb;
    ea << e1.dot(u), e2.dot(u), e1.dot(v), e2.dot(v);
    const Vec3 p = f1.normalized(), q = (f1.cross(f2)).cross(f1).normalized();
    eb << f1.dot(p), f2.dot(p), f1.dot(q), f2.dot(q);
    const Eigen::Matrix2d j = eb * ea.inverse();
    const double det = j.determinant();
    if (!(det > 0) || !std::isfinite(det)) {
      energy += ar * 1e3;
    } else {
      energy += ar * (j.squaredNorm() + j.inverse().squaredNorm()) / 4;
    }
    energy_area += ar;
  }
  out.distortion = energy_area > 0 ? energy / energy_area : 1;
  return out;
}

struct Pose::Impl {
  Eigen::Matrix4d similarity = Eigen::Matrix4d::Identity();
  Eigen::Matrix4d inverse = Eigen::Matrix4d::Identity();
  // A registration: A, A registered, per-vertex turns and both surfaces' trees.
  std::optional<TriMesh> a, moved;
  std::vector<Eigen::Matrix3d> turns;
  std::optional<metro::SurfaceDistance> on_a, on_moved;
};

Pose::Pose() : impl_(std::make_shared<const Impl>()) {}

Pose::Pose(const Eigen::Matrix4d& similarity) {
  auto impl = std::make_shared<Impl>();
  impl->similarity = similarity;
  impl->inverse = similarity.inverse();
  impl_ = std::move(impl);
}

Pose Pose::from_inverse(const Eigen::Matrix4d& inverse) {
  auto impl = std::make_shared<Impl>();
  impl->similarity = inverse.inverse();
  impl->inverse = inverse;
  Pose out;
  out.impl_ = std::move(impl);
  return out;
}

Pose::Pose(const TriMesh& a, Registration registration, int threads) {
  auto impl = std::make_shared<Impl>();
  impl->a = a;
  impl->moved = TriMesh{std::move(registration.positions), a.faces};
  impl->turns = std::move(registration.turn);
  impl->on_a.emplace(*impl->a, "A", threads);
  impl->on_moved.emplace(*impl->moved, "the registered A", threads);
  impl_ = std::move(impl);
}

bool Pose::registered() const { return impl_->a.has_value(); }

Vec3 Pose::forward(const Vec3& x) const { return forward(x, Vec3::Zero()).point; }

Vec3 Pose::inverse(const Vec3& y) const { return inverse(y, Vec3::Zero()).point; }

Pose::Moved Pose::forward(const Vec3& x, const Vec3& n) const {
  const Impl& m = *impl_;
  if (!m.a) return {(m.similarity * x.homogeneous()).head<3>(), m.similarity.topLeftCorner<3, 3>() * n};
  const Located l = locate(*m.a, *m.on_a, x);
  const Tri& t = m.moved->faces[l.face];
  return {l.w[0] * m.moved->positions[t[0]] + l.w[1] * m.moved->positions[t[1]] + l.w[2] * m.moved->positions[t[2]],
          m.turns[nearest_corner(*m.a, l)] * n};
}

Pose::Moved Pose::inverse(const Vec3& y, const Vec3& n) const {
  const Impl& m = *impl_;
  if (!m.a) return {(m.inverse * y.homogeneous()).head<3>(), m.inverse.topLeftCorner<3, 3>() * n};
  const Located l = locate(*m.moved, *m.on_moved, y);
  const Tri& t = m.a->faces[l.face];
  return {l.w[0] * m.a->positions[t[0]] + l.w[1] * m.a->positions[t[1]] + l.w[2] * m.a->positions[t[2]],
          m.turns[nearest_corner(*m.a, l)].transpose() * n};
}

}  // namespace qs::registration
