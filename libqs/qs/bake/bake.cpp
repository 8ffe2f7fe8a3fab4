#include "qs/bake/bake.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/core/parallel.h"

namespace qs::bake {

using remesh::ChartSampler;

const char* to_string(NormalSpace s) { return s == NormalSpace::Tangent ? "tangent" : "object"; }
const char* to_string(GreenChannel g) { return g == GreenChannel::OpenGL ? "opengl" : "directx"; }

OriginalNormals::OriginalNormals(const dissect::Chart& chart, int original_vertices)
    : chart_(&chart), normals_(bake::vertex_normals(chart.mesh)) {
  const TriMesh& m = chart.mesh;
  const int nv = m.num_vertices(), v0 = original_vertices;
  if (v0 < 0 || v0 >= nv) return;
  std::vector<std::vector<int>> neighbours(nv - v0);
  for (const Tri& t : m.faces)
    for (int k = 0; k < 3; ++k)
      if (t[k] >= v0)
        for (int o : {t[(k + 1) % 3], t[(k + 2) % 3]}) {
          auto& n = neighbours[t[k] - v0];
          if (std::find(n.begin(), n.end(), o) == n.end()) n.push_back(o);
        }
  struct Line {
    int v, a, b;
    double t;  // v = (1 - t) a + t b
  };
  std::vector<Line> lines;
  for (int v = v0; v < nv; ++v) {
    const auto& n = neighbours[v - v0];
    const Vec3& p = m.positions[v];
    Line best{v, -1, -1, 0};
    double best_cos = -1 + 1e-8;
    for (size_t i = 0; i < n.size(); ++i)
      for (size_t j = i + 1; j < n.size(); ++j) {
        const Vec3 da = m.positions[n[i]] - p, db = m.positions[n[j]] - p;
        const double la = da.norm(), lb = db.norm();
        if (!(la > 0) || !(lb > 0)) continue;
        const double c = da.dot(db) / (la * lb);
        if (c < best_cos) best_cos = c, best = Line{v, n[i], n[j], la / (la + lb)};
      }
    if (best.a >= 0) lines.push_back(best);
  }
  for (int sweep = 0; sweep < 200; ++sweep) {
    double change = 0;
    for (const Line& l : lines) {
      const Vec3 n = (1 - l.t) * normals_[l.a] + l.t * normals_[l.b];
      change = std::max(change, (n - normals_[l.v]).cwiseAbs().maxCoeff());
      normals_[l.v] = n;
    }
    if (change < 1e-13) break;
  }
}

Vec3 OriginalNormals::at(const ChartSampler::Location& where) const {
  const Tri& t = chart_->mesh.faces[where.face];
  const Vec3 n = where.bary[0] * normals_[t[0]] + where.bary[1] * normals_[t[1]] + where.bary[2] * normals_[t[2]];
  const double len = n.norm();
  return len > 0 ? Vec3(n / len) : Vec3(0, 0, 1);
}

namespace {

// Barycentric weights of q in triangle (a, b, c) (twice-signed-area form).
Vec3 barycentric(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& q) {
  const double area = cross2(b - a, c - a);
  const double wa = cross2(b - q, c - q) / area, wb = cross2(c - q, a - q) / area;
  return {wa, wb, 1.0 - wa - wb};
}

// The value stored for original normal `n` in the frame of the interpolated (not yet normalized)
// T, B, N (see bake.h): m = normalize([t b n]^-1 n) with t = T / |T| etc. Since
// [t b n]^-1 = diag(|T|, |B|, |N|) [T B N]^-1 and [T B N]^-1 has the rows B x N, N x T, T x B over
// det = T . (B x N), m is the normalized (|T| (B x N) . n, |B| (N x T) . n, |N| (T x B) . n) sign(det);
// n's own length does not matter.
Vec3 tangent_space(const Vec3& T, const Vec3& B, const Vec3& N, const Vec3& n) {
  const Vec3 r0 = B.cross(N), r1 = N.cross(T), r2 = T.cross(B);
  const Eigen::Array4d lengths = Eigen::Array4d(T.squaredNorm(), B.squaredNorm(), N.squaredNorm(), 0.0).sqrt();  // packed
  const double lt = lengths[0], lb = lengths[1], ln = lengths[2], det = T.dot(r0);
  Vec3 x;
  if (std::abs(det) > 1e-6 * lt * lb * ln) {
    x = Vec3(lt * r0.dot(n), lb * r1.dot(n), ln * r2.dot(n));
    if (det < 0) x = -x;
  } else {  // degenerate frame: project on an orthonormal one built from the normal alone
    const Vec3 nn = ln > 0 ? Vec3(N / ln) : Vec3(0, 0, 1);
    Vec3 t = T - nn * nn.dot(T);
    if (!(t.norm() > 1e-9 * lt)) t = std::abs(nn.x()) < 0.9 ? Vec3(nn.cross(Vec3::UnitX())) : Vec3(nn.cross(Vec3::UnitY()));
    t.normalize();
    x = Vec3(t.dot(n), nn.cross(t).dot(n), nn.dot(n));
  }
  const double len = x.norm();
  return len > 0 ? Vec3(x * (1.0 / len)) : Vec3(0, 0, 1);
}

Vec3 normalized_or(const Vec3& v, const Vec3& fallback) {
  const double len = v.norm();
  return len > 0 ? Vec3(v / len) : fallback;
}

}  // namespace

BakeResult bake_normal_map(const ChartSampler& sampler, const remesh::SemiRegularConnectivity& connectivity,
                           const std::vector<Vec3>& positions, const BakeOptions& options, const Context& context) {
  BakeResult r;
  r.options = options;
  if (options.tile_sizes.empty()) {
    r.layout = make_atlas_layout(sampler.num_patches(), options.tile_size, options.gutter);
  } else {
    if (static_cast<int>(options.tile_sizes.size()) != sampler.num_patches())
      throw InvalidInput("bake: " + std::to_string(options.tile_sizes.size()) + " tile sizes for " +
                         std::to_string(sampler.num_patches()) + " patches; give one per patch (or none)");
    r.layout = make_atlas_layout(options.tile_sizes, options.tile_size, options.gutter);
  }
  r.mesh = split_by_patch(connectivity, positions, sampler.topology());
  const AtlasLayout& L = r.layout;
  const SplitMesh& m = r.mesh;
  const int np = L.num_patches, W = L.width();
  r.atlas.width = W;
  r.atlas.height = L.height();
  // Texels outside every tile's cell hold the flat normal (0, 0, 1); the tiles overwrite the rest.
  r.atlas.texels.resize(static_cast<size_t>(W) * r.atlas.height * 3);
  for (size_t i = 0; i < r.atlas.texels.size(); i += 3) {
    r.atlas.texels[i] = 0.0f;
    r.atlas.texels[i + 1] = 0.0f;
    r.atlas.texels[i + 2] = 1.0f;
  }

  // Faces per patch; per split vertex its bitangent w (N x T).
  std::vector<std::vector<int>> patch_faces(np);
  for (int f = 0; f < m.num_faces(); ++f) patch_faces[m.face_patch[f]].push_back(f);
  std::vector<Vec3> tangent(m.num_vertices()), bitangent(m.num_vertices());
  for (int i = 0; i < m.num_vertices(); ++i) {
    const auto& t = m.tangents[i];
    tangent[i] = Vec3(t[0], t[1], t[2]);
    bitangent[i] = t[3] * m.normals[i].cross(tangent[i]);
  }
  const OriginalNormals original(sampler.chart(), options.original_vertices);
  const bool tangent_space_map = options.space == NormalSpace::Tangent;
  const double green = options.green == GreenChannel::DirectX ? -1.0 : 1.0;

  // The gutter of a tile: each texel of its cell outside the tile copies the nearest tile texel.
  auto fill_gutter = [&](int p) {
    const int G = L.gutter, x0 = L.tile_x(p), y0 = L.tile_y(p), S = L.tile_side(p);
    for (int y = y0 - G; y < y0 + S + G; ++y) {
      const bool inside_row = y >= y0 && y < y0 + S;
      const int sy = std::clamp(y, y0, y0 + S - 1);
      for (int x = x0 - G; x < x0 + S + G; ++x) {
        if (inside_row && x == x0) x = x0 + S;  // skip the tile itself
        if (x >= x0 + S + G) break;
        const int sx = std::clamp(x, x0, x0 + S - 1);
        const float* in = &r.atlas.texels[3 * (static_cast<size_t>(sy) * W + sx)];
        std::copy(in, in + 3, &r.atlas.texels[3 * (static_cast<size_t>(y) * W + x)]);
      }
    }
  };
  auto bake_patch = [&](int p) {
    std::vector<char> covered;
    const int S = L.tile_side(p);
    const double d = S - 1;
    const int x0 = L.tile_x(p), y0 = L.tile_y(p);
    const std::vector<ChartSampler::Location> where = sampler.locate_grid(p, S, 0.0, 1.0 / d);
    auto store = [&](int ia, int jb, const Vec3& value) {
      float* out = &r.atlas.texels[3 * (static_cast<size_t>(y0 + (S - 1 - jb)) * W + x0 + ia)];
      out[0] = static_cast<float>(value.x());
      out[1] = static_cast<float>(value.y() * (tangent_space_map ? green : 1.0));
      out[2] = static_cast<float>(value.z());
    };
    if (!tangent_space_map) {
      for (int jb = 0; jb < S; ++jb)
        for (int ia = 0; ia < S; ++ia) store(ia, jb, original.at(where[static_cast<size_t>(jb) * S + ia]));
      fill_gutter(p);
      return;
    }
    // The value of texel (ia, jb) at weights w of split face f.
    auto texel = [&](const Tri& t, const Vec3& w, int ia, int jb) {
      const ChartSampler::Location& at = where[static_cast<size_t>(jb) * S + ia];
      const Tri& ct = sampler.chart().mesh.faces[at.face];
      const auto& cn = original.vertex_normals();
      const Vec3 no = at.bary[0] * cn[ct[0]] + at.bary[1] * cn[ct[1]] + at.bary[2] * cn[ct[2]];
      store(ia, jb,
            tangent_space(w[0] * tangent[t[0]] + w[1] * tangent[t[1]] + w[2] * tangent[t[2]],
                          w[0] * bitangent[t[0]] + w[1] * bitangent[t[1]] + w[2] * bitangent[t[2]],
                          w[0] * m.normals[t[0]] + w[1] * m.normals[t[1]] + w[2] * m.normals[t[2]], no));
    };
    // Each remesh face of the patch scans its rows of texel centres (the interval where all three
    // weights are >= -1e-9); a texel on a shared edge goes to the first face that reaches it.
    covered.assign(static_cast<size_t>(S) * S, 0);
    const double eps = 1e-9;
    for (int f : patch_faces[p]) {
      const Tri& t = m.faces[f];
      const Vec2 &a = m.vertex_uv[t[0]], &b = m.vertex_uv[t[1]], &c = m.vertex_uv[t[2]];
      const double lo_y = std::min({a.y(), b.y(), c.y()}), hi_y = std::max({a.y(), b.y(), c.y()});
      const int j0 = std::max(0, static_cast<int>(std::ceil(lo_y * d - 1e-7)));
      const int j1 = std::min(S - 1, static_cast<int>(std::floor(hi_y * d + 1e-7)));
      // Barycentric weights are affine in the texel indices: w = w00 + ia * wi + jb * wj.
      const double inv = 1.0 / cross2(b - a, c - a);
      const Vec3 w00(cross2(b, c) * inv, cross2(c, a) * inv, cross2(a, b) * inv);
      const Vec3 wi = Vec3(b.y() - c.y(), c.y() - a.y(), a.y() - b.y()) * (inv / d);
      const Vec3 wj = Vec3(c.x() - b.x(), a.x() - c.x(), b.x() - a.x()) * (inv / d);
      for (int jb = j0; jb <= j1; ++jb) {
        const Vec3 row = w00 + jb * wj;
        double lo = 0, hi = S - 1;
        for (int k = 0; k < 3; ++k) {
          if (wi[k] > 0) lo = std::max(lo, (-eps - row[k]) / wi[k]);
          else if (wi[k] < 0) hi = std::min(hi, (-eps - row[k]) / wi[k]);
          else if (row[k] < -eps) hi = -1;
        }
        const int i0 = std::max(0, static_cast<int>(std::ceil(lo - 1e-9)));
        const int i1 = std::min(S - 1, static_cast<int>(std::floor(hi + 1e-9)));
        for (int ia = i0; ia <= i1; ++ia) {
          const size_t k = static_cast<size_t>(jb) * S + ia;
          if (covered[k]) continue;
          const Vec3 w = row + ia * wi;
          if (w.minCoeff() < -eps) continue;
          covered[k] = 1;
          texel(t, w, ia, jb);
        }
      }
    }
    for (int jb = 0; jb < S; ++jb)  // rounding gaps: the nearest face, weights clamped
      for (int ia = 0; ia < S; ++ia) {
        if (covered[static_cast<size_t>(jb) * S + ia]) continue;
        const Vec2 q(ia / d, jb / d);
        int best = -1;
        Vec3 best_w(1, 0, 0);
        double score = -1e300;
        for (int f : patch_faces[p]) {
          const Tri& t = m.faces[f];
          const Vec3 w = barycentric(m.vertex_uv[t[0]], m.vertex_uv[t[1]], m.vertex_uv[t[2]], q);
          if (w.minCoeff() > score) score = w.minCoeff(), best = f, best_w = w;
        }
        if (best < 0)
          throw InvalidInput("bake: patch " + std::to_string(p) + " has no remesh face; the remesh and the dissection do not match");
        const Vec3 w = best_w.cwiseMax(0.0);
        texel(m.faces[best], w / w.sum(), ia, jb);
      }
    fill_gutter(p);
  };

  // Patches in parallel; the calling thread reports.
  parallel_for(np, options.threads, context, bake_patch, "bake");
  return r;
}

Rgb8Image quantize8(const NormalAtlas& atlas) {
  Rgb8Image img;
  img.width = atlas.width;
  img.height = atlas.height;
  img.rgb.resize(atlas.texels.size());
  for (size_t i = 0; i < atlas.texels.size(); ++i) {
    const double c = std::clamp(atlas.texels[i] * 0.5 + 0.5, 0.0, 1.0);
    img.rgb[i] = static_cast<unsigned char>(std::lround(c * 255.0));
  }
  return img;
}

Vec3 sample_bilinear(const Rgb8Image& image, const Vec2& st) {
  const double x = st.x() * image.width - 0.5, y = st.y() * image.height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double ax = x - fx, ay = y - fy;
  auto texel = [&](int xi, int yi) -> Vec3 {
    xi = std::clamp(xi, 0, image.width - 1);
    yi = std::clamp(yi, 0, image.height - 1);
    const unsigned char* c = &image.rgb[3 * (static_cast<size_t>(yi) * image.width + xi)];
    return Vec3(c[0], c[1], c[2]) * (2.0 / 255.0) - Vec3::Ones();
  };
  const int xi = static_cast<int>(fx), yi = static_cast<int>(fy);
  return (1 - ay) * ((1 - ax) * texel(xi, yi) + ax * texel(xi + 1, yi)) +
         ay * ((1 - ax) * texel(xi, yi + 1) + ax * texel(xi + 1, yi + 1));
}

ShadingCheck check_shading(const ChartSampler& sampler, const BakeResult& result, const Rgb8Image& map,
                           const ShadingCheckOptions& options) {
  const SplitMesh& m = result.mesh;
  const AtlasLayout& L = result.layout;
  if (map.width != L.width() || map.height != L.height())
    throw InvalidInput("check_shading: the map is " + std::to_string(map.width) + " x " + std::to_string(map.height) +
                       ", the atlas " + std::to_string(L.width()) + " x " + std::to_string(L.height()));
  ShadingCheck out;
  if (options.samples <= 0 || m.num_faces() == 0) return out;
  const OriginalNormals original(sampler.chart(), result.options.original_vertices);
  // Per split vertex what the GLB holds (floats), then what a vertex shader passes on.
  const int ns = m.num_vertices();
  std::vector<Vec3> vn(ns), vt(ns), vb(ns);
  std::vector<Vec2> st(ns);
  auto to_float = [](const Vec3& v) { return Vec3(static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())); };
  for (int i = 0; i < ns; ++i) {
    const auto& t = m.tangents[i];
    vn[i] = to_float(m.normals[i]).normalized();
    vt[i] = to_float(Vec3(t[0], t[1], t[2])).normalized();
    vb[i] = vn[i].cross(vt[i]) * t[3];
    const Vec2 tc = L.texcoord(m.vertex_patch[i], m.vertex_uv[i]);
    st[i] = Vec2(static_cast<float>(tc.x()), static_cast<float>(tc.y()));
  }
  std::vector<double> cdf(m.num_faces());
  double total = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    const Tri& t = m.faces[f];
    total += 0.5 * (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]).norm();
    cdf[f] = total;
  }
  std::mt19937_64 rng(options.seed);
  auto uniform = [&] { return static_cast<double>(rng() >> 11) * 0x1.0p-53; };
  auto angle = [](const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI; };
  const bool tangent_map = result.options.space == NormalSpace::Tangent;
  const double green = result.options.green == GreenChannel::DirectX ? -1.0 : 1.0;
  std::vector<double> with(options.samples), without(options.samples);
  int hint = -1, last_patch = -1;
  for (int s = 0; s < options.samples; ++s) {
    const int f = std::min(m.num_faces() - 1,
                           static_cast<int>(std::upper_bound(cdf.begin(), cdf.end(), uniform() * total) - cdf.begin()));
    const double r1 = std::sqrt(uniform()), r2 = uniform();
    const Vec3 w(1 - r1, r1 * (1 - r2), r1 * r2);
    const Tri& t = m.faces[f];
    const int p = m.face_patch[f];
    const Vec2 uv = (w[0] * m.vertex_uv[t[0]] + w[1] * m.vertex_uv[t[1]] + w[2] * m.vertex_uv[t[2]]).cwiseMax(0.0).cwiseMin(1.0);
    if (p != last_patch) hint = -1;
    const ChartSampler::Location loc = sampler.locate(p, uv, hint);
    hint = loc.face;
    last_patch = p;
    const Vec3 truth = original.at(loc);
    const Vec3 n = normalized_or(w[0] * vn[t[0]] + w[1] * vn[t[1]] + w[2] * vn[t[2]], vn[t[0]]);
    Vec3 c = sample_bilinear(map, w[0] * st[t[0]] + w[1] * st[t[1]] + w[2] * st[t[2]]);
    c.y() *= green;
    Vec3 shaded;
    if (tangent_map) {
      const Vec3 tt = normalized_or(w[0] * vt[t[0]] + w[1] * vt[t[1]] + w[2] * vt[t[2]], vt[t[0]]);
      const Vec3 bb = normalized_or(w[0] * vb[t[0]] + w[1] * vb[t[1]] + w[2] * vb[t[2]], vb[t[0]]);
      shaded = normalized_or(c.x() * tt + c.y() * bb + c.z() * n, n);
    } else {
      shaded = normalized_or(c, n);
    }
    with[s] = angle(shaded, truth);
    without[s] = angle(n, truth);
  }
  auto summarize = [](std::vector<double>& a, double& mean, double& max, double& p95) {
    double sum = 0;
    for (double x : a) sum += x;
    mean = sum / a.size();
    max = *std::max_element(a.begin(), a.end());
    auto k = a.begin() + static_cast<std::ptrdiff_t>(0.95 * (a.size() - 1));
    std::nth_element(a.begin(), k, a.end());
    p95 = *k;
  };
  out.samples = options.samples;
  summarize(with, out.mean_with_map, out.max_with_map, out.p95_with_map);
  summarize(without, out.mean_without_map, out.max_without_map, out.p95_without_map);
  return out;
}

}  // namespace qs::bake
