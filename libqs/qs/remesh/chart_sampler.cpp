#include "qs/remesh/chart_sampler.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <string>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/mesh/connectivity.h"

namespace qs::remesh {

namespace {

// Coordinate along side k (0 at corner k, 1 at corner k+1) and the distance off it.
double side_coordinate(int k, const Vec2& uv) {
  switch (k) {
    case 0: return uv.x();
    case 1: return uv.y();
    case 2: return 1.0 - uv.x();
    default: return 1.0 - uv.y();
  }
}
double side_offset(int k, const Vec2& uv) {
  switch (k) {
    case 0: return uv.y();
    case 1: return 1.0 - uv.x();
    case 2: return 1.0 - uv.y();
    default: return uv.x();
  }
}

// A halfedge on the border of its face's patch.
struct BorderHalfedge {
  int patch, tail, head, other_patch;
  Vec2 uv;  // of the tail, in `patch`
  bool operator<(const BorderHalfedge& o) const { return patch != o.patch ? patch < o.patch : tail < o.tail; }
};

}  // namespace

ChartSampler::ChartSampler(const dissect::Chart& chart, const Context& context) : chart_(&chart) {
  const TriMesh& m = chart.mesh;
  const int nf = m.num_faces(), nv = m.num_vertices();
  if (nf == 0) throw InvalidInput("remesh: the chart mesh has no faces");
  if (static_cast<int>(chart.face_patch.size()) != nf || static_cast<int>(chart.face_uv.size()) != nf)
    throw InvalidInput("remesh: the chart has " + std::to_string(nf) + " faces but " +
                       std::to_string(chart.face_patch.size()) + " patch labels and " +
                       std::to_string(chart.face_uv.size()) + " uv triples; expected one of each per face");
  topology_ = build_base_topology(chart.patches);
  const int np = topology_.num_patches();
  for (int f = 0; f < nf; ++f) {
    if (chart.face_patch[f] < 0 || chart.face_patch[f] >= np)
      throw InvalidInput("remesh: chart face " + std::to_string(f) + " has patch " + std::to_string(chart.face_patch[f]) +
                         "; expected 0.." + std::to_string(np - 1));
    const Tri& t = m.faces[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || t[k] >= nv || t[(k + 1) % 3] == t[k])
        throw InvalidInput("remesh: chart face " + std::to_string(f) + " has an invalid or repeated vertex index");
  }
  for (int c : topology_.chart_vertex)
    if (c >= nv)
      throw InvalidInput("remesh: a patch corner is chart vertex " + std::to_string(c) + " but the chart has " +
                         std::to_string(nv) + " vertices");
  bbox_diagonal_ = bounding_box(m.positions).diagonal();
  context.check_cancel();

  // Faces by patch.
  patch_face_offsets_.assign(np + 1, 0);
  for (int f = 0; f < nf; ++f) ++patch_face_offsets_[chart.face_patch[f] + 1];
  for (int p = 0; p < np; ++p) {
    if (patch_face_offsets_[p + 1] == 0)
      throw InvalidInput("remesh: patch " + std::to_string(p) + " ('" + chart.patches[p].name + "') has no faces");
    patch_face_offsets_[p + 1] += patch_face_offsets_[p];
  }
  patch_faces_.resize(nf);
  {
    std::vector<int> fill(patch_face_offsets_.begin(), patch_face_offsets_.end() - 1);
    for (int f = 0; f < nf; ++f) patch_faces_[fill[chart.face_patch[f]]++] = f;
  }

  // Patch borders: halfedges whose opposite face lies in another patch.
  const auto groups = mesh::group_halfedges(m.faces, nv);
  std::vector<BorderHalfedge> border;
  for (int e = 0; e < groups.num_edges(); ++e) {
    if (groups.size(e) != 2)
      throw InvalidInput("remesh: chart edge " + std::to_string(groups.vertices[e][0]) + "-" +
                         std::to_string(groups.vertices[e][1]) + " has " + std::to_string(groups.size(e)) +
                         " faces; the chart must be a closed manifold mesh");
    const int h0 = groups.halfedges[groups.offsets[e]], h1 = groups.halfedges[groups.offsets[e] + 1];
    const int p0 = chart.face_patch[h0 / 3], p1 = chart.face_patch[h1 / 3];
    if (p0 == p1) continue;
    for (const auto& [h, p, q] : {std::array<int, 3>{h0, p0, p1}, std::array<int, 3>{h1, p1, p0}}) {
      const int f = h / 3, k = h % 3;
      border.push_back({p, m.faces[f][k], m.faces[f][(k + 1) % 3], q, chart.face_uv[f][k]});
    }
  }
  std::sort(border.begin(), border.end());
  for (size_t i = 1; i < border.size(); ++i)
    if (border[i].patch == border[i - 1].patch && border[i].tail == border[i - 1].tail)
      throw InvalidInput("remesh: the border of patch " + std::to_string(border[i].patch) + " ('" +
                         chart.patches[border[i].patch].name + "') passes chart vertex " +
                         std::to_string(border[i].tail) + " twice; a patch must be a disk");

  // Side polylines, traced in each edge's owner patch.
  const int ne = topology_.num_edges();
  edge_vertices_.resize(ne);
  edge_fractions_.resize(ne);
  for (int e = 0; e < ne; ++e) {
    const auto [p, k] = topology_.edge_sides[e][0];
    const int twin = topology_.edge_sides[e][1].patch;
    const int from = chart.patches[p].corners[k], to = chart.patches[p].corners[(k + 1) % 4];
    auto side_name = [&] {
      return "side " + std::to_string(k) + " of patch " + std::to_string(p) + " ('" + chart.patches[p].name + "')";
    };
    auto& verts = edge_vertices_[e];
    auto& fr = edge_fractions_[e];
    const auto first = std::lower_bound(border.begin(), border.end(), BorderHalfedge{p, 0, 0, 0, Vec2::Zero()});
    const auto last = std::lower_bound(border.begin(), border.end(), BorderHalfedge{p + 1, 0, 0, 0, Vec2::Zero()});
    const size_t limit = static_cast<size_t>(last - first);
    for (int v = from; v != to;) {
      const auto it = std::lower_bound(first, last, BorderHalfedge{p, v, 0, 0, Vec2::Zero()});
      if (it == last || it->tail != v || verts.size() > limit)
        throw InvalidInput("remesh: cannot follow " + side_name() + " from chart vertex " + std::to_string(from) +
                           " to " + std::to_string(to) + " along the patch border (stuck at vertex " +
                           std::to_string(v) + ")");
      if (it->other_patch != twin)
        throw InvalidInput("remesh: " + side_name() + " borders patch " + std::to_string(it->other_patch) +
                           " at chart vertex " + std::to_string(v) + ", but its corners say patch " +
                           std::to_string(twin));
      if (std::abs(side_offset(k, it->uv)) > 1e-6)
        throw InvalidInput("remesh: chart vertex " + std::to_string(v) + " on " + side_name() + " has uv (" +
                           std::to_string(it->uv.x()) + ", " + std::to_string(it->uv.y()) +
                           ") off the side of the unit square");
      verts.push_back(v);
      fr.push_back(std::clamp(side_coordinate(k, it->uv), 0.0, 1.0));
      v = it->head;
    }
    verts.push_back(to);
    fr.push_back(1.0);
    fr.front() = 0.0;
    for (size_t i = 1; i < fr.size(); ++i) fr[i] = std::max(fr[i], fr[i - 1]);
  }
  context.check_cancel();

  grid_ = std::make_unique<LocationGrid>();
}

namespace {

// Calls fn(cell) for every cell of a g x g grid over the unit square that the uv triangle may
// touch: row by row, the triangle's u-extent inside the row's strip (padded by a hair), so a
// long diagonal sliver is not entered in its whole bounding box.
template <class Fn>
void for_each_cell(const std::array<Vec2, 3>& uv, int g, Fn&& fn) {
  const double pad = 1e-9;
  auto cell = [g](double x) { return std::clamp(static_cast<int>(std::floor(x * g)), 0, g - 1); };
  const int y0 = cell(std::min({uv[0].y(), uv[1].y(), uv[2].y()}) - pad);
  const int y1 = cell(std::max({uv[0].y(), uv[1].y(), uv[2].y()}) + pad);
  for (int y = y0; y <= y1; ++y) {
    const double lo = static_cast<double>(y) / g - pad, hi = static_cast<double>(y + 1) / g + pad;
    double umin = std::numeric_limits<double>::infinity(), umax = -umin;
    for (int k = 0; k < 3; ++k) {
      const Vec2 &p = uv[k], &q = uv[(k + 1) % 3];
      if (p.y() >= lo && p.y() <= hi) umin = std::min(umin, p.x()), umax = std::max(umax, p.x());
      for (const double yb : {lo, hi})
        if ((p.y() - yb) * (q.y() - yb) < 0) {
          const double u = p.x() + (yb - p.y()) / (q.y() - p.y()) * (q.x() - p.x());
          umin = std::min(umin, u), umax = std::max(umax, u);
        }
    }
    if (!(umin <= umax)) continue;
    for (int x = cell(umin - pad), x1 = cell(umax + pad); x <= x1; ++x) fn(y * g + x);
  }
}

}  // namespace

const ChartSampler::LocationGrid& ChartSampler::grid() const {
  std::call_once(grid_->once, [this] {
    LocationGrid& grid = *grid_;
    const auto& chart = *chart_;
    const int np = num_patches(), nf = chart.mesh.num_faces();
    grid.size.resize(np);
    grid.first.resize(np + 1);
    grid.first[0] = 0;
    for (int p = 0; p < np; ++p) {
      const int n = patch_face_offsets_[p + 1] - patch_face_offsets_[p];
      grid.size[p] = std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)))), 1, 2048);
      grid.first[p + 1] = grid.first[p] + grid.size[p] * grid.size[p];
    }
    grid.offsets.assign(grid.first[np] + 1, 0);
    for (int f = 0; f < nf; ++f) {
      const int p = chart.face_patch[f];
      for_each_cell(chart.face_uv[f], grid.size[p], [&](int c) { ++grid.offsets[grid.first[p] + c + 1]; });
    }
    for (size_t c = 1; c < grid.offsets.size(); ++c) grid.offsets[c] += grid.offsets[c - 1];
    grid.faces.resize(grid.offsets.back());
    std::vector<int> fill(grid.offsets.begin(), grid.offsets.end() - 1);
    for (int f = 0; f < nf; ++f) {
      const int p = chart.face_patch[f];
      for_each_cell(chart.face_uv[f], grid.size[p], [&](int c) { grid.faces[fill[grid.first[p] + c]++] = f; });
    }
  });
  return *grid_;
}

int ChartSampler::best_face(int /*patch*/, const Vec2& q, const int* begin, const int* end, Vec3& bary,
                            double& score) const {
  int best = -1;
  for (const int* it = begin; it != end; ++it) {
    const auto& uv = chart_->face_uv[*it];
    if (try_uv_triangle(uv[0], uv[1], uv[2], q, *it, best, bary, score) && score >= 0)
      break;  // inside (or on the border of) this triangle
  }
  return best;
}

ChartSampler::Location ChartSampler::locate(int patch, const Vec2& uv_in, int hint) const {
  const Vec2 q = uv_in.cwiseMax(0.0).cwiseMin(1.0);
  if (hint >= 0 && hint < static_cast<int>(chart_->face_patch.size()) && chart_->face_patch[hint] == patch) {
    Location loc;
    double score = -1;
    if (best_face(patch, q, &hint, &hint + 1, loc.bary, score) >= 0 && score >= 0) {
      loc.face = hint;
      return loc;
    }
  }
  const LocationGrid& grid = this->grid();
  const int g = grid.size[patch];
  const int x = std::clamp(static_cast<int>(std::floor(q.x() * g)), 0, g - 1);
  const int y = std::clamp(static_cast<int>(std::floor(q.y() * g)), 0, g - 1);
  const int c = grid.first[patch] + y * g + x;
  Location loc;
  double score = -std::numeric_limits<double>::infinity();
  loc.face = best_face(patch, q, grid.faces.data() + grid.offsets[c], grid.faces.data() + grid.offsets[c + 1],
                       loc.bary, score);
  if (score < -1e-9) {  // not inside any face of its cell: rounding gaps; try the whole patch
    const int f = best_face(patch, q, patch_faces_begin(patch), patch_faces_end(patch), loc.bary, score);
    if (f >= 0) loc.face = f;
  }
  if (loc.face < 0)
    throw InvalidInput("remesh: patch " + std::to_string(patch) + " ('" + chart_->patches[patch].name +
                       "') has no face with a positive uv area");
  if (score < 0) {
    loc.bary = loc.bary.cwiseMax(0.0);
    loc.bary /= loc.bary.sum();
  }
  return loc;
}

std::vector<ChartSampler::Location> ChartSampler::locate_grid(int patch, int count, double first, double step) const {
  std::vector<Location> out(static_cast<size_t>(count) * count);
  std::vector<double> score(out.size(), -std::numeric_limits<double>::infinity());
  const double tol = 1e-9;
  auto index_range = [&](double lo, double hi, int& k0, int& k1) {
    k0 = std::max(0, static_cast<int>(std::ceil((lo - first) / step - tol)));
    k1 = std::min(count - 1, static_cast<int>(std::floor((hi - first) / step + tol)));
  };
  for (const int* it = patch_faces_begin(patch); it != patch_faces_end(patch); ++it) {
    const auto& uv = chart_->face_uv[*it];
    const double area = cross2(uv[1] - uv[0], uv[2] - uv[0]);
    if (!(area > 0)) continue;
    int b0, b1;
    index_range(std::min({uv[0].y(), uv[1].y(), uv[2].y()}), std::max({uv[0].y(), uv[1].y(), uv[2].y()}), b0, b1);
    for (int b = b0; b <= b1; ++b) {
      const double v = first + b * step;
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int k = 0; k < 3; ++k) {  // the row's crossing with the triangle's edges
        const Vec2 &p = uv[k], &q = uv[(k + 1) % 3];
        if (std::min(p.y(), q.y()) > v || std::max(p.y(), q.y()) < v) continue;
        const double u = p.y() == q.y() ? p.x() : p.x() + (v - p.y()) / (q.y() - p.y()) * (q.x() - p.x());
        lo = std::min({lo, u, p.y() == q.y() ? q.x() : u});
        hi = std::max({hi, u, p.y() == q.y() ? q.x() : u});
      }
      if (!(lo <= hi)) continue;
      int a0, a1;
      index_range(lo, hi, a0, a1);
      for (int a = a0; a <= a1; ++a) {
        const Vec2 q(first + a * step, v);
        const Vec3 bary = barycentric(uv[0], uv[1], uv[2], q, area);
        const double s = bary.minCoeff();
        const size_t idx = static_cast<size_t>(b) * count + a;
        if (s > score[idx]) {
          score[idx] = s;
          out[idx] = {*it, bary};
        }
      }
    }
  }
  for (size_t idx = 0; idx < out.size(); ++idx) {
    if (score[idx] < -1e-9) {
      const int a = static_cast<int>(idx % count), b = static_cast<int>(idx / count);
      out[idx] = locate(patch, Vec2(first + a * step, first + b * step));
    } else if (score[idx] < 0) {
      out[idx].bary = out[idx].bary.cwiseMax(0.0);
      out[idx].bary /= out[idx].bary.sum();
    }
  }
  return out;
}

Vec3 ChartSampler::position(const Location& loc) const {
  const Tri& f = chart_->mesh.faces[loc.face];
  const auto& pos = chart_->mesh.positions;
  return loc.bary[0] * pos[f[0]] + loc.bary[1] * pos[f[1]] + loc.bary[2] * pos[f[2]];
}

Vec3 ChartSampler::edge_point(int e, double t) const {
  const auto& fr = edge_fractions_[e];
  const auto& vs = edge_vertices_[e];
  const auto& pos = chart_->mesh.positions;
  const size_t i = static_cast<size_t>(std::upper_bound(fr.begin(), fr.end(), t) - fr.begin());
  if (i == 0) return pos[vs.front()];
  if (i >= fr.size()) return pos[vs.back()];
  const double span = fr[i] - fr[i - 1];
  const double a = span > 0 ? (t - fr[i - 1]) / span : 0.0;
  return (1.0 - a) * pos[vs[i - 1]] + a * pos[vs[i]];
}

Vec3 ChartSampler::point(int patch, const Vec2& uv) const {
  int hint = -1;
  return point(patch, uv, hint);
}

Vec3 ChartSampler::point(int patch, const Vec2& uv_in, int& hint) const {
  const Vec2 uv = uv_in.cwiseMax(0.0).cwiseMin(1.0);
  const bool u0 = uv.x() <= 0, u1 = uv.x() >= 1, v0 = uv.y() <= 0, v1 = uv.y() >= 1;
  if ((u0 || u1) && (v0 || v1)) {
    const int k = v0 ? (u0 ? 0 : 1) : (u1 ? 2 : 3);
    return chart_->mesh.positions[chart_->patches[patch].corners[k]];
  }
  if (u0 || u1 || v0 || v1) {
    const int k = v0 ? 0 : u1 ? 1 : v1 ? 2 : 3;
    const double t = side_coordinate(k, uv);
    return edge_point(topology_.side_edge[patch][k], topology_.side_forward[patch][k] ? t : 1.0 - t);
  }
  const Location loc = locate(patch, uv, hint);
  hint = loc.face;
  return position(loc);
}

}  // namespace qs::remesh
