// Per-patch (interior) refinement of a mesh against the reference, and the same-pose pull.
#include "qs/maprefine/map_refine_detail.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/landmarks/landmarks.h"
#include "qs/param/square_param.h"

namespace qs::maprefine::detail {

void check_set(const std::vector<dissect::Dissection>& meshes, const RefineOptions& options) {
  if (meshes.empty()) throw InvalidInput("refine_maps: the set is empty; give the meshes of one dissection");
  if (options.reference < 0 || options.reference >= static_cast<int>(meshes.size()))
    throw InvalidInput("refine_maps: reference mesh " + std::to_string(options.reference) + " is not in the set of " +
                       std::to_string(meshes.size()) + " meshes (expected 0.." + std::to_string(meshes.size() - 1) +
                       ")");
  if (options.iterations < 0 || !(options.tolerance >= 0) || options.border_sweeps < 0 ||
      options.border_iterations < 0 || options.corner_sweeps < 0 || options.corner_iterations < 0)
    throw InvalidInput("refine_maps: iterations (" + std::to_string(options.iterations) + "), tolerance (" +
                       std::to_string(options.tolerance) + "), border sweeps (" +
                       std::to_string(options.border_sweeps) + "), border iterations (" +
                       std::to_string(options.border_iterations) + "), corner sweeps (" +
                       std::to_string(options.corner_sweeps) + ") and corner iterations (" +
                       std::to_string(options.corner_iterations) + ") must be >= 0");
  if (!(options.pose_pull >= 0 && std::isfinite(options.pose_pull)))
    throw InvalidInput("refine_maps: pose pull " + std::to_string(options.pose_pull) +
                       " must be a finite weight >= 0 (0: off)");
  const size_t np = meshes[0].chart.patches.size();
  for (size_t i = 0; i < meshes.size(); ++i) {
    const auto& c = meshes[i].chart;
    const size_t nf = c.mesh.faces.size();
    if (c.patches.size() != np)
      throw InvalidInput("refine_maps: mesh " + std::to_string(i) + " has " + std::to_string(c.patches.size()) +
                         " patches, mesh 0 has " + std::to_string(np) + "; the meshes must come from one dissection");
    if (c.face_patch.size() != nf || c.face_uv.size() != nf)
      throw InvalidInput("refine_maps: mesh " + std::to_string(i) + " has " + std::to_string(nf) + " faces but " +
                         std::to_string(c.face_patch.size()) + " patch labels and " + std::to_string(c.face_uv.size()) +
                         " uv triples");
    for (size_t f = 0; f < nf; ++f) {
      if (c.face_patch[f] < 0 || c.face_patch[f] >= static_cast<int>(np))
        throw InvalidInput("refine_maps: face " + std::to_string(f) + " of mesh " + std::to_string(i) +
                           " has patch " + std::to_string(c.face_patch[f]) + ", expected 0.." +
                           std::to_string(np - 1));
      for (int v : c.mesh.faces[f])
        if (v < 0 || v >= c.mesh.num_vertices())
          throw InvalidInput("refine_maps: face " + std::to_string(f) + " of mesh " + std::to_string(i) +
                             " uses vertex " + std::to_string(v) + " out of range");
    }
  }
}

namespace {

// The patch problems of one mesh (free = patch-interior, not a seed/feature, consistent wedges).
std::vector<PatchProblem> build_problems(const dissect::Dissection& d) {
  const auto& chart = d.chart;
  const int nv = chart.mesh.num_vertices();
  const int np = static_cast<int>(chart.patches.size());
  std::vector<int> first_patch(nv, -1);
  std::vector<char> held(nv, 0);
  for (int f = 0; f < chart.mesh.num_faces(); ++f)
    for (int v : chart.mesh.faces[f]) {
      if (first_patch[v] < 0) first_patch[v] = chart.face_patch[f];
      else if (first_patch[v] != chart.face_patch[f]) held[v] = 1;  // on a patch border
    }
  for (int s : d.seeds)
    if (s >= 0 && s < nv) held[s] = 1;
  for (const auto& f : d.features)
    if (f.vertex >= 0 && f.vertex < nv) held[f.vertex] = 1;
  for (const auto& p : chart.patches)
    for (int c : p.corners)
      if (c >= 0 && c < nv) held[c] = 1;

  std::vector<PatchProblem> probs(np);
  std::vector<std::vector<int>> patch_faces(np);
  for (int f = 0; f < chart.mesh.num_faces(); ++f) patch_faces[chart.face_patch[f]].push_back(f);
  std::vector<int> local(nv, -1);
  for (int p = 0; p < np; ++p) {
    auto& pr = probs[p];
    for (int f : patch_faces[p]) {
      std::array<int, 3> c{};
      for (int k = 0; k < 3; ++k) {
        const int v = chart.mesh.faces[f][k];
        if (local[v] < 0) {
          local[v] = static_cast<int>(pr.vertices.size());
          pr.vertices.push_back(v);
          pr.uv.push_back(chart.face_uv[f][k]);
          pr.var.push_back(held[v] ? -1 : 0);
          pr.dims.push_back(0);
          pr.basis.push_back(Vec2::Zero());
        } else if (pr.uv[local[v]] != chart.face_uv[f][k]) {
          pr.var[local[v]] = -1;  // wedges disagree: hold it
        }
        c[k] = local[v];
      }
      pr.add_face(chart, f, p, c);
    }
    for (size_t v = 0; v < pr.var.size(); ++v)
      if (pr.var[v] == 0) {
        pr.var[v] = pr.unknowns;
        pr.dims[v] = 2;
        pr.unknowns += 2;
      }
    for (int v : pr.vertices) local[v] = -1;
  }
  return probs;
}

// Writes a solved problem's (u, v) into the chart's wedges.
void write_back(const PatchProblem& pr, dissect::Chart& chart) {
  for (size_t t = 0; t < pr.faces.size(); ++t)
    for (int k = 0; k < 3; ++k) chart.face_uv[pr.faces[t]][k] = pr.uv[pr.tri[t][k]];
}

}  // namespace

// ---- The same-pose pull (RefineOptions::pose_pull) -----------------------------------------------

std::vector<PullPatch> build_pull_patches(const dissect::Chart& ref, const RefineOptions& options,
                                          const Context& context) {
  const int np = static_cast<int>(ref.patches.size());
  std::vector<PullPatch> out(np);
  for (int f = 0; f < ref.mesh.num_faces(); ++f) out[ref.face_patch[f]].faces.push_back(f);
  parallel_for(np, options.threads, context, [&](int p) {
    TriMesh m;
    std::unordered_map<int, int> local;
    for (int f : out[p].faces) {
      Tri t{};
      for (int k = 0; k < 3; ++k) {
        const int v = ref.mesh.faces[f][k];
        auto [it, added] = local.try_emplace(v, static_cast<int>(m.positions.size()));
        if (added) m.positions.push_back(ref.mesh.positions[v]);
        t[k] = it->second;
      }
      m.faces.push_back(t);
    }
    if (!m.faces.empty()) out[p].tree.emplace(m, "reference patch");
  });
  return out;
}

// The landmarks' similarity from mesh b to the reference (seeds, then features by name), as
// qs-dissect --same-pose fits it the other way.
Eigen::Matrix4d pose_to_reference(const dissect::Dissection& ref, const dissect::Dissection& b) {
  std::vector<Vec3> from, to;
  for (int k = 0; k < 4; ++k) {
    from.push_back(b.chart.mesh.positions[b.seeds[k]]);
    to.push_back(ref.chart.mesh.positions[ref.seeds[k]]);
  }
  for (const auto& fb : b.features)
    for (const auto& fr : ref.features)
      if (fr.name == fb.name && fb.vertex >= 0 && fr.vertex >= 0) {
        from.push_back(b.chart.mesh.positions[fb.vertex]);
        to.push_back(ref.chart.mesh.positions[fr.vertex]);
      }
  return fit_similarity(from, to);
}

// The reference's point nearest to y (in the reference's frame) within reference patch p, on a
// face that faces as `normal` does (dissect::kSamePoseFacingCos); none when the patch has no such
// face or the nearest point's uv face has zero area.
std::optional<PullTarget> nearest_on_patch(const PosePull& pull, int p, const Vec3& y, const Vec3& normal) {
  const PullPatch& pp = (*pull.patches)[p];
  if (!pp.tree) return std::nullopt;
  const auto hit = pp.tree->closest_facing(y, normal, dissect::kSamePoseFacingCos);
  if (hit.face < 0) return std::nullopt;
  const dissect::Chart& ref = *pull.ref;
  const int f = pp.faces[hit.face];
  const auto& t = ref.mesh.faces[f];
  const auto& fuv = ref.face_uv[f];
  const Vec3& x0 = ref.mesh.positions[t[0]];
  Eigen::Matrix2d ds;
  ds.col(0) = fuv[1] - fuv[0];
  ds.col(1) = fuv[2] - fuv[0];
  if (!(0.5 * ds.determinant() > param::kZeroUvArea)) return std::nullopt;
  const auto b = landmarks::closest_on_triangle(y, x0, ref.mesh.positions[t[1]], ref.mesh.positions[t[2]]);
  Mat32 e;
  e.col(0) = ref.mesh.positions[t[1]] - x0;
  e.col(1) = ref.mesh.positions[t[2]] - x0;
  const Mat32 g = e * ds.inverse();
  return PullTarget{b[0] * fuv[0] + b[1] * fuv[1] + b[2] * fuv[2], g.transpose() * g, hit.distance};
}

// Fills a problem's pull: every local vertex of B with unknowns (free, or sliding along a side)
// that `locate` places gets its target and as weight the pull's weight times a third of its faces'
// area times the metric.
void add_pull(PatchProblem& pr, const dissect::Chart& chart, const PosePull& pull, const PullTargetFn& locate) {
  pr.pull.assign(pr.uv.size(), Eigen::Matrix2d::Zero());
  pr.target.assign(pr.uv.size(), Vec2::Zero());
  std::vector<double> area(pr.uv.size(), 0.0);
  // A free vertex has all its faces here; a sliding wedge those of its own patch.
  std::vector<Vec3> normal(pr.uv.size(), Vec3::Zero());
  std::vector<int> patch(pr.uv.size(), -1);
  for (size_t t = 0; t < pr.tri.size(); ++t) {
    const auto& c = chart.mesh.faces[pr.faces[t]];
    const Vec3 n = (chart.mesh.positions[c[1]] - chart.mesh.positions[c[0]])
                       .cross(chart.mesh.positions[c[2]] - chart.mesh.positions[c[0]]);
    for (int l : pr.tri[t]) area[l] += pr.area[t] / 3, normal[l] += n, patch[l] = pr.face_patch[t];
  }
  for (size_t l = 0; l < pr.uv.size(); ++l) {
    if (pr.dims[l] == 0) continue;
    const Vec3& x = chart.mesh.positions[pr.vertices[l]];
    const auto [y, facing] = pull.pose.inverse(x, normal[l]);
    if (const auto t = locate(patch[l], y, facing)) {
      pr.target[l] = t->uv;
      pr.pull[l] = pull.weight * area[l] * t->metric;
    }
  }
}

namespace {

// add_pull for a problem of one patch's interior: the target in the vertex's own patch.
void add_patch_pull(PatchProblem& pr, const dissect::Chart& chart, const PosePull& pull) {
  if (pr.face_patch.empty()) return;
  const int p = pr.face_patch.front();
  add_pull(pr, chart, pull, [&](int, const Vec3& y, const Vec3& n) { return nearest_on_patch(pull, p, y, n); });
}

// Interior pass: every patch on its own (parallel); returns per patch results.
std::vector<PatchResult> interior_pass(dissect::Dissection& b, const std::vector<ReferencePatch>& refs,
                                       const std::vector<double>& scale, const RefineOptions& options,
                                       bool optimize, const Context& context, const PosePull* pull) {
  std::vector<PatchProblem> probs = build_problems(b);
  std::vector<PatchResult> results(probs.size());
  // Largest patches first: better balance; the result does not depend on the order.
  std::vector<int> order(probs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(),
                   [&](int x, int y) { return probs[x].faces.size() > probs[y].faces.size(); });
  parallel_for(static_cast<int>(order.size()), options.threads, context, [&](int i) {
    const int p = order[i];
    if (pull && optimize) add_patch_pull(probs[p], b.chart, *pull);
    results[p] = solve_problem(probs[p], patch_metric(probs[p], refs, scale), options, optimize);
  });
  for (size_t p = 0; p < probs.size(); ++p)
    if (results[p].changed) write_back(probs[p], b.chart);
  return results;
}

}  // namespace

// Recomputes the figures of the patches marked in `which` (faces, stretch, flipped and zero-area
// uv faces, uv area sum) from the chart, as the dissection computes them, and the mesh's maximum.
void update_figures(dissect::Dissection& b, const std::vector<char>& which) {
  auto& chart = b.chart;
  const int np = static_cast<int>(chart.patches.size());
  std::vector<std::vector<int>> faces_of(np);
  for (int f = 0; f < chart.mesh.num_faces(); ++f) faces_of[chart.face_patch[f]].push_back(f);
  for (int p = 0; p < np; ++p) {
    if (!which[p]) continue;
    std::unordered_map<int, int> local;
    std::vector<Vec3> pos;
    std::vector<Vec2> uv;
    std::vector<Tri> tris;
    for (int f : faces_of[p]) {
      Tri t{};
      for (int k = 0; k < 3; ++k) {
        const int v = chart.mesh.faces[f][k];
        auto [it, added] = local.try_emplace(v, static_cast<int>(pos.size()));
        if (added) {
          pos.push_back(chart.mesh.positions[v]);
          uv.push_back(chart.face_uv[f][k]);
        }
        t[k] = it->second;
      }
      tris.push_back(t);
    }
    param::SquareParam sp;
    sp.uv = uv;
    param::count_uv_faces(tris, sp);
    auto& info = chart.patches[p];
    info.faces = static_cast<int>(tris.size());
    info.stretch = param::l2_stretch(pos, tris, uv).patch;
    info.flipped_faces = sp.flipped_faces;
    info.zero_area_faces = sp.zero_area_faces;
    info.uv_area_sum = sp.uv_area_sum;
  }
  b.max_stretch = 0;
  for (const auto& p : chart.patches) b.max_stretch = std::max(b.max_stretch, p.stretch);
}

// The reference's patches (metric and location grid), built once per reference.
std::vector<ReferencePatch> build_refs(const dissect::Chart& ref, const RefineOptions& options,
                                       const Context& context) {
  const int np = static_cast<int>(ref.patches.size());
  std::vector<std::vector<int>> ref_faces(np);
  for (int f = 0; f < ref.mesh.num_faces(); ++f) ref_faces[ref.face_patch[f]].push_back(f);
  std::vector<std::optional<ReferencePatch>> built(np);
  parallel_for(np, options.threads, context, [&](int p) { built[p].emplace(ref, ref_faces[p]); });
  std::vector<ReferencePatch> refs;
  refs.reserve(np);
  for (auto& r : built) refs.push_back(std::move(*r));
  return refs;
}

MeshResult run_mesh(dissect::Dissection& b, const std::vector<ReferencePatch>& refs, const RefineOptions& options,
                    bool optimize, const Context& context, const PosePull* pull) {
  const int np = static_cast<int>(b.chart.patches.size());
  std::vector<double> area_b(np, 0.0), scale(np, 1.0);
  for (int f = 0; f < b.chart.mesh.num_faces(); ++f) area_b[b.chart.face_patch[f]] += face_area(b.chart.mesh, f);
  for (int p = 0; p < np; ++p)
    if (refs[p].area() > 0) scale[p] = area_b[p] / refs[p].area();

  MeshResult out;
  std::vector<char> changed(np, 0);
  auto note = [&](const std::vector<PatchResult>& rs, bool first) {
    double e = 0, area = 0;
    for (size_t p = 0; p < rs.size(); ++p) {
      e += rs[p].energy_after;
      area += rs[p].area;
      out.steps += rs[p].steps;
      if (rs[p].changed) changed[p] = 1;
      if (first) {
        out.energy_before += rs[p].energy_before;
        out.free += rs[p].free;
        out.held += rs[p].held;
        out.skipped += rs[p].skipped && !rs[p].changed ? 1 : 0;
      }
    }
    out.energy_after = e;
    out.area = area;
  };
  note(interior_pass(b, refs, scale, options, optimize, context, pull), true);
  if (!optimize) return out;
  for (int p = 0; p < np; ++p) out.refined += changed[p];
  update_figures(b, changed);
  return out;
}

}  // namespace qs::maprefine::detail
