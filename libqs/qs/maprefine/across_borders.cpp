// Refinement across patch borders: two patches glued along their shared side, refined as one
// chart and cut again (RefineOptions::across_borders).
#include "qs/maprefine/map_refine_detail.h"

#include <algorithm>
#include <map>

#include "qs/core/parallel.h"
#include "qs/param/square_param.h"

namespace qs::maprefine::detail {

// ---- Refinement across patch borders ----------------------------------------------------------
//
// Two patches P and Q that share exactly one side are glued into one chart on [0,2] x [0,1]: P's
// square turned so that the shared side is its side 1 (u = 1), Q's turned so that the side is its
// side 3 (u = 0) and shifted by 1 in u. B's (u, v) is refined on the union against the reference's
// metric glued the same way, with the shared side's vertices free; then B's union is cut along
// u = 1 into the new P (u <= 1) and Q (u >= 1).

namespace {

struct SharedSide {
  int p = -1, side_p = -1, q = -1, side_q = -1;  // side_p of p runs opposite to side_q of q; p < q
};

// The patch sides shared by two patches that share no other side, in patch order.
std::vector<SharedSide> shared_sides(const dissect::Chart& chart) {
  std::map<std::pair<int, int>, std::pair<int, int>> directed;  // (corner a, corner b) -> (patch, side)
  std::map<std::pair<int, int>, int> twice;
  const int np = static_cast<int>(chart.patches.size());
  for (int p = 0; p < np; ++p)
    for (int k = 0; k < 4; ++k) {
      const auto& c = chart.patches[p].corners;
      const auto key = std::make_pair(c[k], c[(k + 1) % 4]);
      if (!directed.emplace(key, std::make_pair(p, k)).second) ++twice[key];
    }
  std::vector<SharedSide> sides;
  std::map<std::pair<int, int>, int> pair_count;
  for (int p = 0; p < np; ++p)
    for (int k = 0; k < 4; ++k) {
      const auto& c = chart.patches[p].corners;
      const auto key = std::make_pair(c[(k + 1) % 4], c[k]);
      const auto it = directed.find(key);
      if (it == directed.end() || twice.count(key) || twice.count({c[k], c[(k + 1) % 4]})) continue;
      const int q = it->second.first;
      if (q == p) continue;
      if (q < p) continue;
      ++pair_count[{p, q}];
      sides.push_back({p, k, q, it->second.second});
    }
  std::vector<SharedSide> out;
  for (const auto& s : sides)
    if (pair_count[{s.p, s.q}] == 1) out.push_back(s);
  return out;
}

}  // namespace

ChartIndex::ChartIndex(const dissect::Chart& chart) : patch_faces(chart.patches.size()) {
  const int nf = chart.mesh.num_faces();
  vertex_offset.assign(chart.mesh.num_vertices() + 1, 0);
  for (int f = 0; f < nf; ++f) {
    patch_faces[chart.face_patch[f]].push_back(f);
    for (int v : chart.mesh.faces[f]) ++vertex_offset[v + 1];
  }
  for (size_t v = 1; v < vertex_offset.size(); ++v) vertex_offset[v] += vertex_offset[v - 1];
  vertex_faces.resize(vertex_offset.back());
  std::vector<int> fill(vertex_offset.begin(), vertex_offset.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int v : chart.mesh.faces[f]) vertex_faces[fill[v]++] = f;
}

std::vector<int> ChartIndex::gather(const dissect::Chart& chart, const std::vector<int>& patches,
                                      std::vector<char>& outside) const {
  std::vector<int> faces;
  for (int p : patches) faces.insert(faces.end(), patch_faces[p].begin(), patch_faces[p].end());
  std::sort(faces.begin(), faces.end());
  for (int f : faces)
    for (int v : chart.mesh.faces[f])
      for (int i = vertex_offset[v]; i < vertex_offset[v + 1] && !outside[v]; ++i)
        if (std::find(patches.begin(), patches.end(), chart.face_patch[vertex_faces[i]]) == patches.end())
          outside[v] = 1;
  return faces;
}

// Corners, seeds and features of a mesh (#V flags): what the side and corner moves never move.
std::vector<char> pinned_vertices(const dissect::Dissection& d) {
  std::vector<char> pinned(d.chart.mesh.num_vertices(), 0);
  auto pin = [&](int v) {
    if (v >= 0 && v < static_cast<int>(pinned.size())) pinned[v] = 1;
  };
  for (const auto& p : d.chart.patches)
    for (int c : p.corners) pin(c);
  for (int v : d.seeds) pin(v);
  for (const auto& f : d.features) pin(f.vertex);
  return pinned;
}

namespace {

// Refines B's map on the union of the two patches of `side` and plans the cut along the glued line
// u = 1. `pinned`: corners, seeds and features of B (never moved). Only an outcome Refined has a
// cut to commit: the refined union was bijective, lower in energy, and every piece is a positive
// uv triangle inside its square.
SideCut plan_side(const dissect::Chart& chart, const ChartIndex& index, const std::vector<ReferencePatch>& refs,
                  const SharedSide& side, const std::vector<char>& pinned, const RefineOptions& options,
                  const PosePull* pull) {
  SideCut out;
  const int nv = chart.mesh.num_vertices();
  const std::array<Glue, 2> glue = {Glue{side.p, (1 - side.side_p + 4) % 4, 0.0},
                                    Glue{side.q, (3 - side.side_q + 4) % 4, 1.0}};
  std::vector<char> outside(nv, 0);
  const std::vector<int> union_faces = index.gather(chart, {side.p, side.q}, outside);
  // With the pose pull, only the band of the union within kPoseSideBand of the side in u moves:
  // the faces with a corner in the band, the band's edge held.
  const double band = pull ? kPoseSideBand : 1.0;
  double union_area = 0;
  std::vector<int> faces;
  auto in_band = [&](int f) {
    const int w = chart.face_patch[f] == side.p ? 0 : 1;
    for (int k = 0; k < 3; ++k)
      if (std::abs(glue[w].to_glued(chart.face_uv[f][k]).x() - 1) <= band) return true;
    return false;
  };
  for (int f : union_faces) {
    const auto& t = chart.mesh.faces[f];
    double a = 0;
    local_edges(chart.mesh.positions[t[0]], chart.mesh.positions[t[1]], chart.mesh.positions[t[2]], a);
    union_area += a;
    if (in_band(f)) faces.push_back(f);
  }
  // Local vertices (one per chart vertex, glued (u, v)), with their original wedges per patch.
  PatchProblem pr;
  std::unordered_map<int, int> local;
  std::vector<std::array<char, 2>> in_patch;
  std::vector<std::array<Vec2, 2>> wedge;
  std::vector<char> held;
  for (int f : faces) {
    const int w = chart.face_patch[f] == side.p ? 0 : 1;
    std::array<int, 3> c{};
    for (int k = 0; k < 3; ++k) {
      const int v = chart.mesh.faces[f][k];
      const Vec2& s = chart.face_uv[f][k];
      const Vec2 g = glue[w].to_glued(s);
      auto [it, added] = local.try_emplace(v, static_cast<int>(pr.vertices.size()));
      const int l = it->second;
      if (added) {
        pr.vertices.push_back(v);
        pr.uv.push_back(g);
        in_patch.push_back({0, 0});
        wedge.emplace_back();
        held.push_back(outside[v] || pinned[v] || std::abs(g.x() - 1) > band);
      }
      if (!in_patch[l][w]) {
        in_patch[l][w] = 1;
        wedge[l][w] = s;
        if (in_patch[l][1 - w]) {
          // On both patches: must be on the shared side, at the same glued point.
          if (std::abs(g.x() - 1) > 1e-9 || std::abs(pr.uv[l].x() - 1) > 1e-9 || std::abs(g.y() - pr.uv[l].y()) > 1e-9)
            return out.with(SideOutcome::Skipped);  // the patches meet elsewhere too, or disagree along the side
          pr.uv[l] = Vec2(1, glue[0].to_glued(wedge[l][0]).y());
        }
      } else if (wedge[l][w] != s) {
        held[l] = 1;  // wedges of one patch disagree: hold it
      }
      c[k] = l;
    }
    pr.add_face(chart, f, chart.face_patch[f], c);
  }
  // A vertex of both patches off the shared side (checked above) cannot occur; the side's own
  // vertices become interior unknowns unless pinned.
  pr.add_unknowns(held);
  const int nl = static_cast<int>(pr.vertices.size());
  if (pr.unknowns == 0) return out.with(SideOutcome::Unchanged);
  // The reference's metric on the same union, scaled by area_B(union) / area_A(union).
  const double area_a = refs[side.p].area() + refs[side.q].area();
  const double scale = area_a > 0 ? union_area / area_a : 1.0;
  const std::array<Eigen::Matrix2d, 2> lin = {glue[0].linear(), glue[1].linear()};
  auto hints = std::make_shared<std::vector<std::array<int, 2>>>(pr.faces.size(), std::array<int, 2>{-1, -1});
  const MetricFn metric = [&, hints](size_t t, const Vec2& g) {
    const int w = g.x() <= 1 ? 0 : 1;
    const Vec2 s = glue[w].to_patch(g);
    return Eigen::Matrix2d(scale * lin[w] * refs[glue[w].patch].metric(s, (*hints)[t][w]) * lin[w].transpose());
  };
  if (pull) {
    // The pose pull toward the nearer of the reference's two patches, in glued (u, v).
    add_pull(pr, chart, *pull, [&](int, const Vec3& y, const Vec3& n) {
      return nearest_of(
          *pull, 2, y, n, [&](int w) { return glue[w].patch; },
          [&](int w, const PullTarget& t) {
            return PullTarget{glue[w].to_glued(t.uv), lin[w] * t.metric * lin[w].transpose(), t.distance};
          });
    });
  }
  const std::vector<Vec2> start = pr.uv;
  RefineOptions side_options = options;
  side_options.iterations = std::min(options.iterations, options.border_iterations);
  const PatchResult res = solve_problem(pr, metric, side_options, true, Vec2(2, 1));
  out.steps = res.steps;
  if (res.skipped) return out.with(SideOutcome::Skipped);
  if (!res.changed) return out.with(SideOutcome::Unchanged);
  std::vector<Vec2> uv = pr.uv;
  for (int l = 0; l < nl; ++l)
    if (held[l]) uv[l] = start[l];  // exactly as they were

  // Snap free vertices within kCutSnap of a crossing edge's u-extent onto the cut line (when
  // their faces stay positive and their ring's energy grows by at most kSnapEnergyGrowth), so
  // that the cut makes fewer slivers. (Without the energy bound a snap could flatten a ring:
  // gen-s3's distortion to mesh 0 went 1.051 -> 2.418 instead of -> 1.023.)
  std::vector<std::vector<int>> vertex_faces(nl);
  for (size_t t = 0; t < pr.tri.size(); ++t)
    for (int l : pr.tri[t]) vertex_faces[l].push_back(static_cast<int>(t));
  std::vector<Mat46> ring_a(pr.tri.size());
  std::vector<char> ring_have(pr.tri.size(), 0);
  auto ring = [&](int l) {
    double e = 0;
    for (int t : vertex_faces[l]) {
      if (!ring_have[t]) ring_a[t] = metric_jacobian(pr, t, metric), ring_have[t] = 1;
      e += face_energy(pr, t, ring_a[t], Eigen::Vector4d::Zero(), uv);
    }
    return e;
  };
  auto faces_positive = [&](int l) {
    for (int t : vertex_faces[l]) {
      const auto& c = pr.tri[t];
      if (!(0.5 * tri_det(uv[c[0]], uv[c[1]], uv[c[2]]) > 4 * param::kZeroUvArea)) return false;
    }
    return true;
  };
  std::vector<int> snap;
  for (const auto& c : pr.tri)
    for (int k = 0; k < 3; ++k) {
      const int a = c[k], bb = c[(k + 1) % 3];
      const double ua = uv[a].x() - 1, ub = uv[bb].x() - 1;
      if (!(ua * ub < 0)) continue;
      const double t = ua / (ua - ub);
      if (t < kCutSnap && !held[a]) snap.push_back(a);
      if (t > 1 - kCutSnap && !held[bb]) snap.push_back(bb);
    }
  std::sort(snap.begin(), snap.end());
  snap.erase(std::unique(snap.begin(), snap.end()), snap.end());
  for (int l : snap) {
    const Vec2 was = uv[l];
    const double before = ring(l);
    uv[l].x() = 1;
    if (!faces_positive(l) || !(ring(l) <= (1 + kSnapEnergyGrowth) * before)) uv[l] = was;
  }

  // Cut points: one per crossing edge, computed from its lower chart vertex.
  std::map<std::pair<int, int>, int> cut;  // (local a, local b), a < b -> new local id
  std::vector<Vec3> new_pos;
  std::vector<Vec2> all_uv = uv;
  auto cut_point = [&](int a, int bb) {
    if (pr.vertices[a] > pr.vertices[bb]) std::swap(a, bb);
    const auto key = std::make_pair(a, bb);
    const auto it = cut.find(key);
    if (it != cut.end()) return it->second;
    const double ua = uv[a].x() - 1, ub = uv[bb].x() - 1;
    const double t = ua / (ua - ub);
    const int id = static_cast<int>(all_uv.size());
    all_uv.emplace_back(1.0, (1 - t) * uv[a].y() + t * uv[bb].y());
    new_pos.push_back((1 - t) * chart.mesh.positions[pr.vertices[a]] + t * chart.mesh.positions[pr.vertices[bb]]);
    cut.emplace(key, id);
    return id;
  };
  auto sign = [&](int l) { return all_uv[l].x() < 1 ? -1 : all_uv[l].x() > 1 ? 1 : 0; };
  std::vector<SideCut::Piece> pieces;
  for (size_t t = 0; t < pr.tri.size(); ++t) {
    const auto& c = pr.tri[t];
    const int f = pr.faces[t];
    std::array<int, 3> sg{sign(c[0]), sign(c[1]), sign(c[2])};
    const bool neg = sg[0] < 0 || sg[1] < 0 || sg[2] < 0, pos = sg[0] > 0 || sg[1] > 0 || sg[2] > 0;
    if (!(neg && pos)) {
      pieces.push_back({f, c});
      continue;
    }
    int zero = -1;
    for (int k = 0; k < 3; ++k)
      if (sg[k] == 0) zero = k;
    if (zero >= 0) {  // the line passes through corner `zero`: two triangles
      const int a = c[zero], x = c[(zero + 1) % 3], y = c[(zero + 2) % 3];
      const int m = cut_point(x, y);
      pieces.push_back({f, {a, x, m}});
      pieces.push_back({f, {a, m, y}});
      continue;
    }
    int lone = 0;  // the corner alone on its side
    for (int k = 0; k < 3; ++k)
      if (sg[k] != sg[(k + 1) % 3] && sg[k] != sg[(k + 2) % 3]) lone = k;
    const int a = c[lone], x = c[(lone + 1) % 3], y = c[(lone + 2) % 3];
    const int m1 = cut_point(a, x), m2 = cut_point(y, a);
    pieces.push_back({f, {a, m1, m2}});
    // The quad m1 x y m2 (convex): the diagonal whose smaller triangle is larger.
    const double d1 = std::min(tri_det(all_uv[m1], all_uv[x], all_uv[y]), tri_det(all_uv[m1], all_uv[y], all_uv[m2]));
    const double d2 = std::min(tri_det(all_uv[m1], all_uv[x], all_uv[m2]), tri_det(all_uv[m2], all_uv[x], all_uv[y]));
    if (d1 >= d2) {
      pieces.push_back({f, {m1, x, y}});
      pieces.push_back({f, {m1, y, m2}});
    } else {
      pieces.push_back({f, {m1, x, m2}});
      pieces.push_back({f, {m2, x, y}});
    }
  }
  // Each piece's patch and wedge (u, v); held vertices keep their original wedges exactly.
  std::vector<int> piece_patch(pieces.size());
  std::vector<std::array<Vec2, 3>> piece_uv(pieces.size());
  for (size_t i = 0; i < pieces.size(); ++i) {
    int w = -1;
    for (int l : pieces[i].c)
      if (sign(l) != 0) w = sign(l) < 0 ? 0 : 1;
    if (w < 0) return out.with(SideOutcome::Skipped);  // a piece on the line itself: degenerate
    piece_patch[i] = glue[w].patch;
    for (int k = 0; k < 3; ++k) {
      const int l = pieces[i].c[k];
      piece_uv[i][k] = l < nl && held[l] && in_patch[l][w] ? wedge[l][w] : glue[w].to_patch(all_uv[l]);
    }
    const auto& q = piece_uv[i];
    if (!(0.5 * tri_det(q[0], q[1], q[2]) > param::kZeroUvArea)) return out.with(SideOutcome::Skipped);
  }
  out.vertices = std::move(pr.vertices);
  out.new_pos = std::move(new_pos);
  out.pieces = std::move(pieces);
  out.piece_patch = std::move(piece_patch);
  out.piece_uv = std::move(piece_uv);
  return out.with(SideOutcome::Refined);
}

}  // namespace

// Writes a planned cut into the chart: new vertices appended, each face of the union replaced by
// its pieces (the first keeps the face id, the others appended).
void commit_side(dissect::Chart& chart, const SideCut& cut) {
  const int nl = static_cast<int>(cut.vertices.size());
  const int first_new = chart.mesh.num_vertices();
  auto chart_vertex = [&](int l) { return l < nl ? cut.vertices[l] : first_new + (l - nl); };
  for (const auto& p : cut.new_pos) chart.mesh.positions.push_back(p);
  int last_face = -1;
  for (size_t i = 0; i < cut.pieces.size(); ++i) {
    const auto& pc = cut.pieces[i];
    const Tri t{chart_vertex(pc.c[0]), chart_vertex(pc.c[1]), chart_vertex(pc.c[2])};
    if (pc.face != last_face) {
      last_face = pc.face;
      chart.mesh.faces[last_face] = t;
      chart.face_patch[last_face] = cut.piece_patch[i];
      chart.face_uv[last_face] = cut.piece_uv[i];
    } else {
      chart.mesh.faces.push_back(t);
      chart.face_patch.push_back(cut.piece_patch[i]);
      chart.face_uv.push_back(cut.piece_uv[i]);
    }
  }
}

// `border_sweeps` passes over the shared sides of B. The sides are grouped (in patch order, each
// into the first group that has neither of its patches), the sides of a group are planned in
// parallel (their unions share no face) and committed in order: the result does not depend on
// the thread count.
AcrossResult refine_across(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                           const RefineOptions& options, const Context& context, const PosePull* pull) {
  AcrossResult out;
  const auto sides = shared_sides(b.chart);
  std::vector<std::vector<int>> groups;
  {
    std::vector<std::vector<char>> used;
    const size_t np = b.chart.patches.size();
    for (size_t i = 0; i < sides.size(); ++i) {
      size_t g = 0;
      while (g < groups.size() && (used[g][sides[i].p] || used[g][sides[i].q])) ++g;
      if (g == groups.size()) {
        groups.emplace_back();
        used.emplace_back(np, 0);
      }
      groups[g].push_back(static_cast<int>(i));
      used[g][sides[i].p] = used[g][sides[i].q] = 1;
    }
  }
  for (int sweep = 0; sweep < options.border_sweeps; ++sweep) {
    std::vector<char> pinned = pinned_vertices(b);
    int refined = 0;
    for (const auto& group : groups) {
      pinned.resize(b.chart.mesh.num_vertices(), 0);
      const ChartIndex index(b.chart);
      std::vector<SideCut> cuts(group.size());
      parallel_for(static_cast<int>(group.size()), options.threads, context, [&](int i) {
        cuts[i] = plan_side(b.chart, index, refs, sides[group[i]], pinned, options, pull);
      });
      for (const auto& cut : cuts) {
        out.steps += cut.steps;
        if (cut.outcome == SideOutcome::Refined) {
          commit_side(b.chart, cut);
          out.added_vertices += static_cast<int>(cut.new_pos.size());
          ++refined;
        }
        if (sweep == 0 && cut.outcome == SideOutcome::Skipped) ++out.sides_skipped;
      }
    }
    out.sides_refined += refined;
    if (refined == 0) break;
  }
  return out;
}

}  // namespace qs::maprefine::detail
