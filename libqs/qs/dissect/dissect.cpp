// The dissect module's entry points (paper 3.2-3.4). The work is spread over files by role:
// mesh_dissector.cpp (one mesh's cut mesh and leaves), quinary_split.cpp (cutting one patch),
// split_choice.cpp (where to split), feature_alignment.cpp (the warp of features across a set),
// leaf_repair.cpp (untangling, stretch minimization), set_dissector.cpp (the union tree).
//
// The working state is one CutMesh whose faces carry a patch label (one label per quinary-tree
// node). A split only ever inserts vertices strictly inside the parent patch (its cuts start at
// the parent's corners and otherwise stay in its interior), so neighbouring patches never change
// and every patch side stays shared by exactly two patches: the base domain is conforming by
// construction, and checked anyway.

#include <string>
#include <unordered_map>

#include "qs/core/error.h"
#include "qs/dissect/dissect_detail.h"
#include "qs/dissect/dissection.h"

namespace qs::dissect {

const char* stop_reason_name(StopReason r) {
  switch (r) {
    case StopReason::None: return "none";
    case StopReason::MaxDepth: return "max_depth";
    case StopReason::TooFewFaces: return "too_few_faces";
    case StopReason::SplitFailed: return "split_failed";
    case StopReason::NoProgress: return "no_progress";
    case StopReason::SmallArea: return "small_area";
  }
  return "none";
}

BaseDomain build_base_domain(const std::vector<PatchInfo>& patches) {
  BaseDomain bd;
  std::unordered_map<int, int> base_of;  // chart vertex -> base vertex, by first appearance
  for (const auto& p : patches)
    for (int c : p.corners)
      if (base_of.emplace(c, static_cast<int>(bd.vertices.size())).second) bd.vertices.push_back(c);
  std::vector<std::pair<int, int>> sides;
  for (const auto& p : patches) {
    std::array<int, 4> q;
    for (int k = 0; k < 4; ++k) q[k] = base_of.at(p.corners[k]);
    bd.quads.push_back(q);
    for (int k = 0; k < 4; ++k) sides.emplace_back(q[k], q[(k + 1) % 4]);
  }
  std::sort(sides.begin(), sides.end());
  bool ok = std::adjacent_find(sides.begin(), sides.end()) == sides.end();  // no side twice one way
  for (const auto& [a, b] : sides) ok = ok && std::binary_search(sides.begin(), sides.end(), std::make_pair(b, a));
  bd.closed_conforming = ok;
  bd.edges = static_cast<int>(sides.size()) / 2;
  bd.euler_characteristic = static_cast<int>(bd.vertices.size()) - bd.edges + static_cast<int>(bd.quads.size());
  return bd;
}

DissectionSet dissect_set(const std::vector<MeshToDissect>& meshes, const DissectOptions& options,
                          const Context& context) {
  if (!(options.tau >= 1.0)) throw InvalidInput("--tau must be at least 1 (the stretch of an isometry)");
  if (!(options.min_split_area >= 0 && options.min_split_area <= 1))
    throw InvalidInput("min_split_area is " + std::to_string(options.min_split_area) +
                       "; expected a fraction of the surface in [0, 1] (0: off)");
  if (!(options.force_split_area >= 0 && options.force_split_area <= 1))
    throw InvalidInput("force_split_area is " + std::to_string(options.force_split_area) +
                       "; expected a fraction of the surface in [0, 1] (0: off)");
  if (options.area_extra_depth < 0 || options.area_extra_depth > 12)
    throw InvalidInput("area_extra_depth is " + std::to_string(options.area_extra_depth) +
                       "; expected 0 (off) to 12 levels past max_depth");
  if (!(options.protrusion_stretch >= 0))
    throw InvalidInput("protrusion_stretch is " + std::to_string(options.protrusion_stretch) +
                       "; expected a stretch >= 0 (0: off)");
  if (meshes.empty()) throw InvalidInput("no mesh to dissect");
  for (const auto& m : meshes)
    if (m.mesh == nullptr) throw InvalidInput("dissect_set: a mesh is null");
  auto folded = [&meshes](const DissectionSet& s, std::string* where) {
    long n = 0;
    for (size_t i = 0; i < s.meshes.size(); ++i)
      for (const auto& p : s.meshes[i].chart.patches) {
        const int f = p.flipped_faces + p.zero_area_faces;
        if (f > 0 && where && where->empty())
          *where = "patch " + p.name + " of " + (meshes[i].name.empty() ? "mesh " + std::to_string(i) : meshes[i].name);
        n += f;
      }
    return n;
  };
  auto run = [&](const DissectOptions& o) {
    DissectionSet r = detail::SetDissector(meshes, o, context).run();
    r.geodesic_seed_curves = o.geodesic_seed_curves;
    r.intrinsic_cotan = o.intrinsic_cotan;
    return r;
  };
  DissectionSet out = run(options);
  std::string where;
  long bad = folded(out, &where);
  // The safety nets: a folded result is dissected again with safer options, and the result that
  // folds less is kept. First same_pose (posed corners change the children, and so the tree)
  // off, then the new maps off (edge paths and mean-value weights).
  DissectOptions used = options;
  auto try_again = [&](DissectOptions o, const std::string& how, std::string DissectionSet::*why,
                       const std::string& what) {
    context.info("dissection: " + std::to_string(bad) + " folded uv faces with " + what + " (" + where +
                 "); dissecting again with " + how);
    DissectionSet alt = run(o);
    std::string alt_where;
    const long alt_bad = folded(alt, &alt_where);
    if (alt_bad >= bad) return;
    alt.same_pose_fallback = out.same_pose_fallback;
    alt.*why = std::to_string(bad) + " folded uv faces with " + what + " (" + where + ")";
    out = std::move(alt);
    bad = alt_bad;
    where = alt_where;
    used = o;
  };
  if (bad > 0 && options.same_pose && meshes.size() > 1) {
    DissectOptions o = used;
    o.same_pose = false;
    try_again(o, "the common (u,v)", &DissectionSet::same_pose_fallback, "posed corners");
  }
  if (bad > 0 && options.fallback_maps && (options.geodesic_seed_curves || options.intrinsic_cotan)) {
    DissectOptions o = used;
    o.geodesic_seed_curves = false;
    o.intrinsic_cotan = false;
    try_again(o, "edge+mean-value", &DissectionSet::maps_fallback,
              maps_name(options.geodesic_seed_curves, options.intrinsic_cotan));
  }
  return out;
}

std::string maps_name(bool geodesic_seed_curves, bool intrinsic_cotan) {
  return std::string(geodesic_seed_curves ? "geodesic" : "edge") + "+" + (intrinsic_cotan ? "cotan" : "mean-value");
}

Dissection dissect(const TriMesh& mesh, const std::optional<std::array<int, 4>>& seeds,
                   const DissectOptions& options, const Context& context) {
  MeshToDissect m;
  m.mesh = &mesh;
  m.seeds = seeds;
  DissectionSet set = dissect_set({m}, options, context);
  return std::move(set.meshes.front());
}

}  // namespace qs::dissect
