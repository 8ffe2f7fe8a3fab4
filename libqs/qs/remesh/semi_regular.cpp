#include "qs/remesh/semi_regular.h"

#include "qs/remesh/chart_sampler.h"

namespace qs::remesh {

std::vector<Vec3> sample_positions(const ChartSampler& sampler, const SemiRegularConnectivity& connectivity,
                                   const Context& context) {
  const int nv = connectivity.num_vertices();
  std::vector<Vec3> positions(nv);
  int hint = -1;  // consecutive interior vertices are neighbours in one patch
  for (int v = 0; v < nv; ++v) {
    if ((v & 0xffff) == 0xffff) context.check_cancel();
    positions[v] = sampler.point(connectivity.vertex_patch[v], connectivity.vertex_uv[v], hint);
  }
  return positions;
}

}  // namespace qs::remesh
