#include "qs/dfi/pipeline.h"

#include <cmath>
#include <string>

#include "qs/core/error.h"
#include "qs/mesh/validate.h"

namespace qs::dfi {
namespace {

// Volume centroid of a closed outward mesh (signed tetrahedra about the bounding-box centre).
Vec3 volume_centroid(const TriMesh& m, double& volume) {
  const Box3 box = bounding_box(m.positions);
  const Vec3 o = 0.5 * (box.min + box.max);
  Vec3 c = Vec3::Zero();
  double v = 0;
  for (const Tri& t : m.faces) {
    const Vec3 a = m.positions[t[0]] - o, b = m.positions[t[1]] - o, d = m.positions[t[2]] - o;
    const double vol = a.dot(b.cross(d)) / 6.0;
    v += vol;
    c += vol * (a + b + d) / 4.0;
  }
  volume = v;
  return v != 0 ? Vec3(o + c / v) : o;
}

}  // namespace

Vec3 placement(const Similarity& s, double t, const Vec3& y) {
  const double scale = (1 - t) + t * s.scale;
  const Vec3 centre_to = s.to, centre_from = (1 - t) * s.to + t * s.from;
  return centre_from + (y - centre_to) / scale;
}

PreparedMorph prepare_morph(const TriMesh& source, const TriMesh& target, const MorphOptions& options,
                            const Context& ctx) {
  if (options.grid < 8 || options.grid > 1024)
    throw InvalidInput("grid is " + std::to_string(options.grid) + " cells; expected 8 to 1024");
  if (options.pad < 2) throw InvalidInput("pad is " + std::to_string(options.pad) + " cells; expected at least 2");
  PreparedMorph m;
  const Vec3 c0 = volume_centroid(source, m.source_volume);
  const Vec3 c1 = volume_centroid(target, m.target_volume);
  if (!(m.source_volume > 0) || !(m.target_volume > 0))
    throw InvalidInput("a shape encloses no volume (source " + std::to_string(m.source_volume) + ", target " +
                       std::to_string(m.target_volume) + ")");
  if (options.align == Align::Similarity) {
    m.target_to_source.scale = std::cbrt(m.source_volume / m.target_volume);
    m.target_to_source.from = c1;
    m.target_to_source.to = c0;
  }
  TriMesh moved = target;
  for (Vec3& p : moved.positions) p = m.target_to_source.apply(p);
  Box3 box = bounding_box(source.positions);
  const Box3 b1 = bounding_box(moved.positions);
  box.min = box.min.cwiseMin(b1.min);
  box.max = box.max.cwiseMax(b1.max);
  const Grid domain = grid_over(box, options.grid, options.pad);
  ctx.report("distance fields", 0.0);
  m.source_sdf = signed_distance(source, domain, options.sdf, ctx.without_progress());
  ctx.report("distance fields", 0.5);
  m.target_sdf = signed_distance(moved, domain, options.sdf, ctx.without_progress());
  ctx.report("distance fields", 1.0);
  return m;
}

Grid blend_field(const PreparedMorph& m, double t) {
  Grid g = m.source_sdf;
  for (size_t i = 0; i < g.values.size(); ++i)
    g.values[i] = static_cast<float>((1 - t) * m.source_sdf.values[i] + t * m.target_sdf.values[i]);
  return g;
}

TriMesh frame_mesh(const PreparedMorph& m, const Grid& field, double t, const PolygonizeOptions& options) {
  TriMesh mesh = polygonize(field, options);
  for (Vec3& p : mesh.positions) p = placement(m.target_to_source, t, p);
  return mesh;
}

}  // namespace qs::dfi
