// Normal-map baking on coarse remeshes of shapes made in code: texel values checked against the
// true surface normals, decoded as a viewer would (the exported frame, 8-bit values).
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "qs/bake/atlas.h"
#include "qs/bake/bake.h"
#include "qs/bake/export_glb.h"
#include "qs/bake/image_io.h"
#include "qs/bake/split_mesh.h"
#include "../common/image_test_support.h"
#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/remesh/chart_sampler.h"
#include "qs/remesh/quality.h"
#include "qs/remesh/uniform.h"
#include "qs/shapes/shapes.h"

namespace fs = std::filesystem;
using qs::Vec2;
using qs::Vec3;
using namespace qs::bake;
using ::testing::HasSubstr;

namespace {

double angle_deg(const Vec3& a, const Vec3& b) { return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI; }

struct Fixture {
  int input_vertices = 0;  // the chart keeps the input's vertices first
  qs::dissect::Dissection dissection;
  qs::remesh::SemiRegular remesh;
  std::unique_ptr<qs::remesh::ChartSampler> sampler;
};

Fixture make(const qs::TriMesh& mesh, double tau, int level, int max_depth = 6) {
  Fixture f;
  qs::dissect::DissectOptions o;
  o.tau = tau;
  o.max_depth = max_depth;
  o.max_patch_area = 0;      // patches by stretch alone, mean-value maps: the fixtures' designs
  o.stretch_iterations = 0;
  f.input_vertices = mesh.num_vertices();
  f.dissection = qs::dissect::dissect(mesh, std::nullopt, o);
  f.remesh = qs::remesh::remesh_uniform(f.dissection.chart, level);
  f.sampler = std::make_unique<qs::remesh::ChartSampler>(f.dissection.chart);
  return f;
}

// An ellipsoid (semi-axes kAxes), both seed patches split once (10 patches), level 3.
const Vec3 kAxes(1.6, 1.0, 0.7);
const Fixture& sphere() {
  static const Fixture f = make(qs::shapes::ellipsoid(kAxes.x(), kAxes.y(), kAxes.z(), 6), 1.25, 3, 1);
  return f;
}
// The exact normal of that ellipsoid at (or radially nearest to) p.
Vec3 true_normal(const Vec3& p) { return p.cwiseQuotient(kAxes.cwiseProduct(kAxes)).normalized(); }

BakeResult bake(const Fixture& f, BakeOptions o) {
  o.original_vertices = f.input_vertices;
  return bake_normal_map(*f.sampler, f.remesh.connectivity, f.remesh.positions, o);
}

// Brute force, independent of the baker: the split face of `patch` whose (u,v) triangle holds uv.
std::pair<int, Vec3> find_face(const SplitMesh& m, int patch, const Vec2& uv) {
  int best = -1;
  Vec3 best_w;
  double best_s = -1e300;
  for (int f = 0; f < m.num_faces(); ++f) {
    if (m.face_patch[f] != patch) continue;
    const auto& t = m.faces[f];
    const Vec2 a = m.vertex_uv[t[0]], b = m.vertex_uv[t[1]], c = m.vertex_uv[t[2]];
    auto cr = [](const Vec2& x, const Vec2& y) { return x.x() * y.y() - x.y() * y.x(); };
    const double area = cr(b - a, c - a);
    const Vec3 w(cr(b - uv, c - uv) / area, cr(c - uv, a - uv) / area, cr(a - uv, b - uv) / area);
    if (w.minCoeff() > best_s) best_s = w.minCoeff(), best = f, best_w = w;
  }
  return {best, best_w};
}

// What a glTF viewer shows for decoded map value c at a point of split face f.
Vec3 shade(const SplitMesh& m, int f, const Vec3& w, const Vec3& c) {
  const auto& t = m.faces[f];
  Vec3 n = Vec3::Zero(), tt = Vec3::Zero(), bb = Vec3::Zero();
  for (int k = 0; k < 3; ++k) {
    const auto& g = m.tangents[t[k]];
    const Vec3 tk(g[0], g[1], g[2]);
    n += w[k] * m.normals[t[k]];
    tt += w[k] * tk;
    bb += w[k] * g[3] * m.normals[t[k]].cross(tk);
  }
  return (c.x() * tt.normalized() + c.y() * bb.normalized() + c.z() * n.normalized()).normalized();
}

Vec3 decode8(const Rgb8Image& img, int x, int y) {
  const unsigned char* p = &img.rgb[3 * (static_cast<size_t>(y) * img.width + x)];
  return Vec3(p[0], p[1], p[2]) * (2.0 / 255.0) - Vec3::Ones();
}

}  // namespace

TEST(AtlasLayout, GridColumnsAndTexelCentres) {
  for (int p = 1; p <= 50; ++p) {
    const AtlasLayout a = make_atlas_layout(p, 16, 3);
    EXPECT_EQ(a.columns, static_cast<int>(std::ceil(std::sqrt(p) - 1e-12))) << p;
    EXPECT_GE(a.columns * a.rows, p);
    EXPECT_LT(a.columns * (a.rows - 1), p) << "no empty row";
    EXPECT_EQ(a.width(), a.columns * 22);
  }
  const AtlasLayout a = make_atlas_layout(7, 8, 2);  // 3 x 3 cells of 12
  EXPECT_EQ(a.tile_x(4), 12 + 2);
  EXPECT_EQ(a.tile_y(4), 12 + 2);
  // Texel (i, j) centre <-> (u, v) <-> texture coordinates of that centre.
  for (int i : {0, 3, 7})
    for (int j : {0, 5, 7}) {
      const Vec2 uv = a.texel_uv(4, i, j);
      const Vec2 px = a.pixel(4, uv);
      EXPECT_NEAR(px.x(), a.tile_x(4) + i + 0.5, 1e-12);
      EXPECT_NEAR(px.y(), a.tile_y(4) + j + 0.5, 1e-12);
      const Vec2 st = a.texcoord(4, uv);
      EXPECT_NEAR(st.x() * a.width(), px.x(), 1e-9);
      EXPECT_NEAR(st.y() * a.height(), px.y(), 1e-9);
    }
  EXPECT_EQ(a.texel_uv(4, 0, 0), Vec2(0, 1)) << "top-left texel is u = 0, v = 1";
  EXPECT_EQ(a.texel_uv(4, 7, 7), Vec2(1, 0));
}

TEST(AtlasLayout, TileSizesFollowTheSquareRootOfTheArea) {
  // Areas 1 : 4 : 16 : 0.25 -> sides - 1 in ratio 1 : 2 : 4 : 0.5, P tiles' worth of texels.
  const std::vector<double> area = {1, 4, 16, 0.25};
  const std::vector<int> s = tile_sizes_by_area(area, 65);
  ASSERT_EQ(s.size(), 4u);
  const double unit = 64 * std::sqrt(4.0 / 21.25);
  for (size_t p = 0; p < area.size(); ++p)
    EXPECT_NEAR(s[p] - 1, unit * std::sqrt(area[p]), 0.5) << p;
  // Texels per unit area, (S_p - 1)^2 / a_p, within rounding of each other.
  for (size_t p = 1; p < area.size(); ++p) {
    const double ratio = (s[p] - 1.0) * (s[p] - 1.0) / area[p] / ((s[0] - 1.0) * (s[0] - 1.0) / area[0]);
    EXPECT_NEAR(ratio, 1.0, 0.1) << p;
  }
  EXPECT_EQ(tile_sizes_by_area({1, 1, 1}, 9), (std::vector<int>{9, 9, 9}));
  EXPECT_EQ(tile_sizes_by_area({1, 0}, 64)[1], 4) << "at least 4 texels";
  EXPECT_THROW(tile_sizes_by_area({}, 64), qs::InvalidInput);
  EXPECT_THROW(tile_sizes_by_area({0, 0}, 64), qs::InvalidInput);
  EXPECT_THROW(tile_sizes_by_area({1, -1}, 64), qs::InvalidInput);
  EXPECT_THROW(tile_sizes_by_area({1, std::nan("")}, 64), qs::InvalidInput);
}

TEST(AtlasLayout, ShelvesHoldEveryTileOnceWithoutOverlap) {
  const std::vector<int> sides = {17, 5, 33, 9, 9, 64, 4, 12, 33, 20};
  const int G = 3;
  const AtlasLayout a = make_atlas_layout(sides, 16, G);
  EXPECT_FALSE(a.grid);
  ASSERT_EQ(a.num_patches, 10);
  long long used = 0;
  for (int p = 0; p < a.num_patches; ++p) {
    EXPECT_EQ(a.tile_side(p), sides[p]);
    // The cell (tile and gutter) lies in the image.
    EXPECT_GE(a.tile_x(p) - G, 0);
    EXPECT_GE(a.tile_y(p) - G, 0);
    EXPECT_LE(a.tile_x(p) + sides[p] + G, a.width());
    EXPECT_LE(a.tile_y(p) + sides[p] + G, a.height());
    used += (sides[p] + 2LL * G) * (sides[p] + 2LL * G);
    for (int q = 0; q < p; ++q) {
      const bool apart = a.tile_x(p) + sides[p] + G <= a.tile_x(q) - G || a.tile_x(q) + sides[q] + G <= a.tile_x(p) - G ||
                         a.tile_y(p) + sides[p] + G <= a.tile_y(q) - G || a.tile_y(q) + sides[q] + G <= a.tile_y(p) - G;
      EXPECT_TRUE(apart) << "cells of patches " << p << " and " << q << " overlap";
    }
    // Texel centres and texture coordinates as in the grid.
    const Vec2 px = a.pixel(p, a.texel_uv(p, sides[p] - 1, 0));
    EXPECT_NEAR(px.x(), a.tile_x(p) + sides[p] - 0.5, 1e-12);
    EXPECT_NEAR(px.y(), a.tile_y(p) + 0.5, 1e-12);
  }
  EXPECT_GE(static_cast<double>(used) / (static_cast<double>(a.width()) * a.height()), 0.5) << "packing wastes half";
  // Deterministic: the same sides give the same layout.
  const AtlasLayout b = make_atlas_layout(sides, 16, G);
  for (int p = 0; p < a.num_patches; ++p) EXPECT_TRUE(a.tile_x(p) == b.tile_x(p) && a.tile_y(p) == b.tile_y(p));
  EXPECT_THROW(make_atlas_layout(std::vector<int>{}, 16, 2), qs::InvalidInput);
  EXPECT_THROW(make_atlas_layout(std::vector<int>{8, 1}, 16, 2), qs::InvalidInput);
  EXPECT_THROW(make_atlas_layout(std::vector<int>{8, 8}, 16, -1), qs::InvalidInput);
  EXPECT_THROW(make_atlas_layout(std::vector<int>(100, 8192), 16, 4), qs::InvalidInput);
}

TEST(AtlasLayout, RejectsBadSizes) {
  EXPECT_THROW(make_atlas_layout(0, 16, 2), qs::InvalidInput);
  EXPECT_THROW(make_atlas_layout(4, 1, 2), qs::InvalidInput);
  EXPECT_THROW(make_atlas_layout(4, 16, -1), qs::InvalidInput);
  try {
    make_atlas_layout(100, 8192, 4);
    FAIL() << "no throw";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("smaller tile size"));
  }
}

TEST(SplitMesh, CopiesPerPatchKeepPositionsAndTileEachSquare) {
  const Fixture& f = sphere();
  const auto& c = f.remesh.connectivity;
  const SplitMesh m = split_by_patch(c, f.remesh.positions, f.sampler->topology());
  ASSERT_GT(c.num_patches, 2);
  ASSERT_EQ(m.num_faces(), c.num_faces());
  std::vector<double> area(c.num_patches, 0.0);
  std::map<int, int> copies;
  for (int s = 0; s < m.num_vertices(); ++s) {
    ++copies[m.source_vertex[s]];
    EXPECT_EQ(m.positions[s], f.remesh.positions[m.source_vertex[s]]);
    const Vec3 t(m.tangents[s][0], m.tangents[s][1], m.tangents[s][2]);
    EXPECT_NEAR(t.norm(), 1, 1e-9);
    EXPECT_NEAR(t.dot(m.normals[s]), 0, 1e-9);
    EXPECT_EQ(m.tangents[s][3], 1.0) << "outward faces with counter-clockwise (u,v): right-handed";
  }
  for (int fi = 0; fi < m.num_faces(); ++fi) {
    const auto& t = m.faces[fi];
    for (int k = 0; k < 3; ++k) EXPECT_EQ(m.source_vertex[t[k]], c.faces[fi][k]);
    const Vec2 e1 = m.vertex_uv[t[1]] - m.vertex_uv[t[0]], e2 = m.vertex_uv[t[2]] - m.vertex_uv[t[0]];
    const double a = 0.5 * (e1.x() * e2.y() - e1.y() * e2.x());
    EXPECT_GT(a, 0) << "face " << fi;
    area[m.face_patch[fi]] += a;
  }
  for (double a : area) EXPECT_NEAR(a, 1.0, 1e-12) << "a patch's faces tile its unit square";
  // Interior vertices once, side vertices twice, base vertices once per patch around them.
  const auto& topo = f.sampler->topology();
  for (int v = 0; v < c.num_vertices(); ++v) {
    const Vec2 uv = c.vertex_uv[v];
    const bool on_u = uv.x() == 0 || uv.x() == 1, on_v = uv.y() == 0 || uv.y() == 1;
    const int expected = on_u && on_v ? topo.valence[v] : (on_u || on_v ? 2 : 1);
    EXPECT_EQ(copies[v], expected) << "vertex " << v;
  }
}

TEST(SplitMesh, RejectsMismatchedRemesh) {
  const Fixture& f = sphere();
  auto c = f.remesh.connectivity;
  EXPECT_THROW(split_by_patch(c, std::vector<Vec3>(3), f.sampler->topology()), qs::InvalidInput);
  std::swap(c.faces[0][1], c.faces[0][2]);  // clockwise in every patch
  try {
    split_by_patch(c, f.remesh.positions, f.sampler->topology());
    FAIL() << "no throw";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("remesh face 0"));
  }
}

TEST(OriginalNormals, InsertedVerticesFollowTheInputsSmoothField) {
  const Fixture& f = sphere();
  const auto& chart = f.dissection.chart;
  ASSERT_GT(chart.mesh.num_vertices(), f.input_vertices + 100) << "the cuts should have inserted vertices";
  const OriginalNormals plain(chart), interpolated(chart, f.input_vertices);
  double sum_plain = 0, sum_interpolated = 0;
  for (int v = 0; v < chart.mesh.num_vertices(); ++v) {
    const Vec3 truth = true_normal(chart.mesh.positions[v]);
    if (v < f.input_vertices) {
      ASSERT_EQ(plain.vertex_normals()[v], interpolated.vertex_normals()[v]) << "input vertices keep theirs";
      continue;
    }
    sum_plain += angle_deg(plain.vertex_normals()[v], truth);
    sum_interpolated += angle_deg(interpolated.vertex_normals()[v], truth);
  }
  const int inserted = chart.mesh.num_vertices() - f.input_vertices;
  EXPECT_LT(sum_interpolated / inserted, 0.25 * sum_plain / inserted)
      << "mean angle to the true normal at inserted vertices: " << sum_interpolated / inserted << " vs "
      << sum_plain / inserted << " degrees";
}

TEST(Bake, EllipsoidTexelCentresDecodeToTheTrueNormal) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 32;
  o.gutter = 3;
  const BakeResult r = bake(f, o);
  const Rgb8Image img = quantize8(r.atlas);
  const AtlasLayout& L = r.layout;
  double worst = 0, worst_flat = 0;
  for (int p = 0; p < L.num_patches; ++p)
    for (int j = 0; j < L.tile_size; ++j)
      for (int i = 0; i < L.tile_size; ++i) {
        const Vec2 uv = L.texel_uv(p, i, j);
        const Vec3 truth = true_normal(f.sampler->point(p, uv));
        const auto [face, w] = find_face(r.mesh, p, uv);
        ASSERT_GE(face, 0);
        const Vec3 c = decode8(img, L.tile_x(p) + i, L.tile_y(p) + j);
        worst = std::max(worst, angle_deg(shade(r.mesh, face, w, c), truth));
        worst_flat = std::max(worst_flat, angle_deg(shade(r.mesh, face, w, Vec3(0, 0, 1)), truth));
      }
  EXPECT_LT(worst, 1.0);
  EXPECT_GT(worst_flat, 2.0) << "the coarse normals alone should be visibly off (else the test proves nothing)";
}

TEST(Bake, ObjectSpaceTexelsAreTheTrueNormal) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 16;
  o.space = NormalSpace::Object;
  const BakeResult r = bake(f, o);
  const Rgb8Image img = quantize8(r.atlas);
  double worst = 0;
  for (int p = 0; p < r.layout.num_patches; ++p)
    for (int j = 0; j < 16; ++j)
      for (int i = 0; i < 16; ++i) {
        const Vec3 truth = true_normal(f.sampler->point(p, r.layout.texel_uv(p, i, j)));
        worst = std::max(worst, angle_deg(decode8(img, r.layout.tile_x(p) + i, r.layout.tile_y(p) + j), truth));
      }
  EXPECT_LT(worst, 1.0);
}

TEST(Bake, GuttersAreFilledAndBorderReadsStayClose) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 64;
  o.gutter = 4;
  const BakeResult r = bake(f, o);
  const AtlasLayout& L = r.layout;
  ASSERT_LT(L.num_patches, L.columns * L.rows) << "want an unused cell in the grid for this test";
  const Rgb8Image img = quantize8(r.atlas);
  // No background: every texel decodes to a unit vector.
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double len = decode8(img, x, y).norm();
      ASSERT_NEAR(len, 1.0, 0.02) << "texel " << x << ", " << y;
    }
  const int S = L.tile_size, G = L.gutter;
  for (int p = 0; p < L.num_patches; ++p) {
    const int x0 = L.tile_x(p), y0 = L.tile_y(p);
    // Each gutter texel repeats the nearest tile texel.
    for (int y = y0 - G; y < y0 + S + G; ++y)
      for (int x = x0 - G; x < x0 + S + G; ++x) {
        const int sx = std::clamp(x, x0, x0 + S - 1), sy = std::clamp(y, y0, y0 + S - 1);
        ASSERT_EQ(r.atlas.at(x, y), r.atlas.at(sx, sy)) << "patch " << p << " texel " << x << ", " << y;
      }
    // Bilinear reads on the tile's border (between texel centres too), and up to G - 0.5 texels
    // beyond it, equal the read on the border and decode close to the true normal there (no
    // bleeding from the neighbour cell; what is left is the map's own interpolation error).
    for (int k = 0; k <= 40; ++k) {
      const double t = k / 40.0;
      for (const Vec2& uv : {Vec2(0, t), Vec2(1, t), Vec2(t, 0), Vec2(t, 1)}) {
        const Vec2 st = L.texcoord(p, uv);
        const Vec3 on = sample_bilinear(img, st);
        const auto [face, w] = find_face(r.mesh, p, uv);
        EXPECT_LT(angle_deg(shade(r.mesh, face, w, on), true_normal(f.sampler->point(p, uv))), 1.5) << "patch " << p << " uv " << uv.transpose();
        const Vec2 out((uv.x() == 0 ? -1 : uv.x() == 1 ? 1 : 0), (uv.y() == 0 ? 1 : uv.y() == 1 ? -1 : 0));  // pixels
        const Vec2 beyond = st + out.cwiseQuotient(Vec2(L.width(), L.height())) * (G - 0.5);
        EXPECT_LT((sample_bilinear(img, beyond) - on).norm(), 1e-9) << "patch " << p << " uv " << uv.transpose();
      }
    }
  }
}

TEST(Bake, AreaSizedTilesAreBakedWithGuttersAndEvenTexelDensity) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 24;
  o.gutter = 2;
  o.space = NormalSpace::Object;
  const std::vector<double> share = qs::remesh::patch_area_shares({&f.dissection.chart});
  double sum = 0;
  for (double a : share) sum += a;
  EXPECT_NEAR(sum, 1.0, 1e-9) << "one mesh: the shares of its surface";
  o.tile_sizes = tile_sizes_by_area(share, o.tile_size);
  const BakeResult r = bake(f, o);
  const AtlasLayout& L = r.layout;
  EXPECT_FALSE(L.grid);
  const Rgb8Image img = quantize8(r.atlas);
  double worst = 0;
  for (int p = 0; p < L.num_patches; ++p) {
    const int S = L.tile_side(p), G = L.gutter, x0 = L.tile_x(p), y0 = L.tile_y(p);
    EXPECT_EQ(S, o.tile_sizes[p]);
    for (int j = 0; j < S; ++j)
      for (int i = 0; i < S; ++i) {
        const Vec3 truth = true_normal(f.sampler->point(p, L.texel_uv(p, i, j)));
        worst = std::max(worst, angle_deg(decode8(img, x0 + i, y0 + j), truth));
      }
    for (int y = y0 - G; y < y0 + S + G; ++y)
      for (int x = x0 - G; x < x0 + S + G; ++x)
        ASSERT_EQ(r.atlas.at(x, y), r.atlas.at(std::clamp(x, x0, x0 + S - 1), std::clamp(y, y0, y0 + S - 1)));
  }
  EXPECT_LT(worst, 1.5);
  // The same atlas on one thread and on three (patches are baked in parallel).
  BakeOptions one = o, three = o;
  one.threads = 1;
  three.threads = 3;
  EXPECT_EQ(bake(f, one).atlas.texels, bake(f, three).atlas.texels);
  for (int y = 0; y < img.height; ++y)  // outside the cells: the flat normal, a unit vector too
    for (int x = 0; x < img.width; ++x) ASSERT_NEAR(decode8(img, x, y).norm(), 1.0, 0.02);
  // Texel density: per patch (S_p - 1)^2 per unit square. Sizing by area evens it out.
  std::vector<double> sized(L.num_patches);
  for (int p = 0; p < L.num_patches; ++p) sized[p] = L.tile_side(p) - 1.0;
  const auto even = qs::remesh::chart_density(f.dissection.chart, sized);
  const auto grid = qs::remesh::chart_density(f.dissection.chart, o.tile_size - 1.0);
  EXPECT_LE(even.spread, grid.spread + 1e-9);
  EXPECT_LE(even.p5, even.p50);
  EXPECT_LE(even.p50, even.p95);
}

TEST(Bake, DirectXFlipsGreenOnly) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 16;
  const Rgb8Image gl = quantize8(bake(f, o).atlas);
  o.green = GreenChannel::DirectX;
  const Rgb8Image dx = quantize8(bake(f, o).atlas);
  ASSERT_EQ(gl.rgb.size(), dx.rgb.size());
  int differ = 0;
  for (size_t i = 0; i < gl.rgb.size(); i += 3) {
    EXPECT_EQ(gl.rgb[i], dx.rgb[i]);
    EXPECT_EQ(gl.rgb[i + 2], dx.rgb[i + 2]);
    EXPECT_NEAR(dx.rgb[i + 1], 255 - gl.rgb[i + 1], 1);
    differ += gl.rgb[i + 1] != dx.rgb[i + 1];
  }
  EXPECT_GT(differ, static_cast<int>(gl.rgb.size() / 3 / 4)) << "green should mostly change";
}

TEST(Bake, ThreadsGiveIdenticalAtlases) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 20;
  o.threads = 1;
  const BakeResult a = bake(f, o);
  o.threads = 3;
  EXPECT_EQ(a.atlas.texels, bake(f, o).atlas.texels);
}

TEST(Bake, MapRestoresTheDetailOfABumpySphere) {
  const Fixture f = make(qs::shapes::bumpy_sphere(0.08, 5, 5), 1.5, 2);
  BakeOptions o;
  o.tile_size = 64;
  const BakeResult r = bake(f, o);
  const ShadingCheck c = check_shading(*f.sampler, r, quantize8(r.atlas), {20000, 7});
  EXPECT_EQ(c.samples, 20000);
  EXPECT_GT(c.mean_without_map, 5.0);
  EXPECT_LT(c.mean_with_map, 1.5);
  EXPECT_LT(c.mean_with_map, c.mean_without_map / 4);
  // A map of the wrong green convention, read as OpenGL, must do worse: the check decodes for real.
  BakeResult wrong = r;
  for (size_t i = 1; i < wrong.atlas.texels.size(); i += 3) wrong.atlas.texels[i] = -wrong.atlas.texels[i];
  EXPECT_GT(check_shading(*f.sampler, r, quantize8(wrong.atlas), {20000, 7}).mean_with_map, 2 * c.mean_with_map);
  // Deterministic.
  const ShadingCheck again = check_shading(*f.sampler, r, quantize8(r.atlas), {20000, 7});
  EXPECT_EQ(again.mean_with_map, c.mean_with_map);
}

TEST(Bake, CancelFlagStops) {
  const Fixture& f = sphere();
  std::atomic<bool> cancel{true};
  qs::Context ctx;
  ctx.cancel = &cancel;
  EXPECT_THROW(bake_normal_map(*f.sampler, f.remesh.connectivity, f.remesh.positions, {}, ctx), qs::Error);
}

TEST(ImageIo, RoundTripsEveryFormat) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 8;
  o.gutter = 1;
  const BakeResult r = bake(f, o);
  const fs::path dir = fs::temp_directory_path() / ("qs_bake_image_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (ImageFormat fmt : {ImageFormat::Png8, ImageFormat::Png16, ImageFormat::Exr}) {
    const auto bytes = encode_image(r.atlas, fmt);
    const fs::path path = dir / (std::string("m") + file_suffix(fmt));
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    const NormalAtlas back = read_normal_image(path);
    ASSERT_EQ(back.width, r.atlas.width);
    ASSERT_EQ(back.height, r.atlas.height);
    const double tol = fmt == ImageFormat::Png8 ? 1.01 / 255 : fmt == ImageFormat::Png16 ? 1.01 / 65535 : 1e-6;
    double worst = 0;
    for (size_t i = 0; i < back.texels.size(); ++i) worst = std::max(worst, static_cast<double>(std::abs(back.texels[i] - r.atlas.texels[i])));
    EXPECT_LT(worst, tol) << to_string(fmt);
  }
  EXPECT_EQ(read_rgb8(dir / "m_normal.png").rgb, quantize8(r.atlas).rgb);
  EXPECT_THROW(read_normal_image(dir / "missing.png"), qs::IoError);
  fs::remove_all(dir);
}

TEST(ExportGlb, CarriesTheFrameAndTexcoordsTheBakeUsed) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 16;
  const BakeResult r = bake(f, o);
  const auto png = encode_png8(quantize8(r.atlas));
  const qs::gltf::Mesh g = to_gltf_mesh(r, png, "ellipsoid");
  const fs::path path = fs::temp_directory_path() / ("qs_bake_export_" + std::to_string(::getpid()) + ".glb");
  qs::gltf::write_glb(path, g);
  const qs::gltf::Mesh back = qs::gltf::read_glb(path);
  fs::remove(path);
  ASSERT_EQ(back.positions.size(), static_cast<size_t>(r.mesh.num_vertices()));
  ASSERT_EQ(back.faces, r.mesh.faces);
  ASSERT_EQ(back.texcoords.size(), back.positions.size());
  ASSERT_EQ(back.tangents.size(), back.positions.size());
  ASSERT_TRUE(back.material && back.material->normal_texture);
  EXPECT_EQ(back.material->normal_texture->bytes, png);
  std::map<int, Vec3> where;  // split copies of one remesh vertex stay at one position
  for (int i = 0; i < r.mesh.num_vertices(); ++i) {
    const Vec2 st = r.layout.texcoord(r.mesh.vertex_patch[i], r.mesh.vertex_uv[i]);
    EXPECT_NEAR((back.texcoords[i] - st).norm(), 0, 1e-6);
    EXPECT_NEAR((back.normals[i] - r.mesh.normals[i]).norm(), 0, 1e-6);
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(back.tangents[i][k], r.mesh.tangents[i][k], 1e-6);
    const auto [it, fresh] = where.emplace(r.mesh.source_vertex[i], back.positions[i]);
    if (!fresh) {
      EXPECT_EQ(it->second, back.positions[i]);
    }
  }
  // An object-space bake gets no normalTexture (glTF has none for object space).
  o.space = NormalSpace::Object;
  const BakeResult obj = bake(f, o);
  const qs::gltf::Mesh go = to_gltf_mesh(obj, encode_png8(quantize8(obj.atlas)), "ellipsoid");
  ASSERT_TRUE(go.material.has_value());
  EXPECT_FALSE(go.material->normal_texture.has_value());
  EXPECT_EQ(go.texcoords.size(), go.positions.size());
}

// A damaged normal map gives one line in qs's words: the file, what is wrong, what was expected,
// and none of the image library's own text; a missing one is an i/o error.
TEST(ImageIo, DamagedMapsAreInvalidInputInQsWords) {
  const Fixture& f = sphere();
  BakeOptions o;
  o.tile_size = 8;
  const BakeResult r = bake(f, o);
  const fs::path dir = fs::temp_directory_path() / ("qs_bad_map_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir / name, std::ios::binary) << bytes;
    return dir / name;
  };
  const auto as_string = [](const std::vector<unsigned char>& v) { return std::string(v.begin(), v.end()); };
  const std::string png = as_string(encode_image(r.atlas, ImageFormat::Png8));
  const std::string exr = as_string(encode_image(r.atlas, ImageFormat::Exr));
  std::string bad_crc = png;
  bad_crc[30] ^= 1;  // the IHDR chunk's checksum
  const struct {
    fs::path path;
    std::string what;
  } cases[] = {
      {write("truncated.png", png.substr(0, png.size() / 2)), "the PNG ends early"},
      {write("crc.png", bad_crc), "damaged PNG"},
      {write("header.png", std::string("\x89PNG\r\n\x1a\n") + "0000garbage"), "the PNG ends early"},
      {write("text.png", "v 0 0 0\n"), "not an image qs reads"},
      {write("truncated.exr", exr.substr(0, exr.size() - 7)), "the OpenEXR file ends early"},
  };
  for (const auto& c : cases) {
    try {
      read_normal_image(c.path);
      ADD_FAILURE() << "expected InvalidInput for " << c.path;
    } catch (const qs::InvalidInput& e) {
      const std::string m = e.what();
      EXPECT_EQ(m.rfind(c.path.string() + ": " + c.what, 0), 0u) << m;
      EXPECT_NE(m.find("expected a normal map"), std::string::npos) << m;
      EXPECT_EQ(m.find('\n'), std::string::npos) << m;
      EXPECT_EQ(qs::test::quoted_library_phrase(m), "") << m;
    }
  }
  EXPECT_THROW(read_rgb8(dir / "crc.png"), qs::InvalidInput);
  EXPECT_THROW(read_normal_image(dir), qs::IoError);
  fs::remove_all(dir);
}
