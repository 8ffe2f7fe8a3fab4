#pragma once
// Every invariant of a dissection, computed independently of the implementation.

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "qs/core/geometry2d.h"
#include "qs/dissect/dissection.h"
#include "qs/mesh/validate.h"

namespace qs::testing {

using qs::dissect::Dissection;

// Checks every invariant of a dissection, computed independently of the implementation.
inline void check_dissection(const Dissection& d, int input_faces) {
  const auto& c = d.chart;
  const int nf = c.mesh.num_faces();
  ASSERT_GE(nf, input_faces);
  ASSERT_EQ(c.face_patch.size(), static_cast<size_t>(nf));
  // The cut mesh is still a valid closed genus-0 mesh.
  const auto v = qs::mesh::validate(c.mesh);
  EXPECT_TRUE(v.report.accepted) << qs::mesh::format_report("chart", v.report);
  EXPECT_FALSE(v.report.orientation_flipped);

  const int np = static_cast<int>(c.patches.size());
  std::vector<double> area(np, 0.0);
  std::vector<int> faces(np, 0);
  for (int f = 0; f < nf; ++f) {
    const int p = c.face_patch[f];
    ASSERT_GE(p, 0);
    ASSERT_LT(p, np);  // every face in exactly one patch
    const auto& uv = c.face_uv[f];
    const double a = 0.5 * cross2(uv[1] - uv[0], uv[2] - uv[0]);
    area[p] += a;
    ++faces[p];
    EXPECT_GT(a, 0.0) << "face " << f << " of patch " << c.patches[p].name << " is flipped or degenerate";
  }
  // Corner uv: the corner vertices sit at the square's corners in their own patch.
  const std::array<qs::Vec2, 4> square = {qs::Vec2(0, 0), qs::Vec2(1, 0), qs::Vec2(1, 1), qs::Vec2(0, 1)};
  for (int p = 0; p < np; ++p) {
    EXPECT_NEAR(area[p], 1.0, 1e-9) << c.patches[p].name;
    EXPECT_EQ(faces[p], c.patches[p].faces);
    EXPECT_EQ(c.patches[p].flipped_faces, 0);
  }
  std::vector<int> found(4 * np, 0);
  for (int f = 0; f < nf; ++f) {
    const auto& info = c.patches[c.face_patch[f]];
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 4; ++i)
        if (c.mesh.faces[f][k] == info.corners[i]) {
          EXPECT_LT((c.face_uv[f][k] - square[i]).norm(), 1e-12) << info.name << " corner " << i;
          found[4 * c.face_patch[f] + i] = 1;
        }
  }
  for (int x : found) EXPECT_EQ(x, 1);

  // Each patch's boundary is one loop, through its 4 corners in counter-clockwise order.
  std::map<std::pair<int, int>, int> edge_face;
  for (int f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) edge_face[{c.mesh.faces[f][k], c.mesh.faces[f][(k + 1) % 3]}] = f;
  std::vector<std::map<int, int>> next(np);
  for (const auto& [e, f] : edge_face) {
    const int g = edge_face.at({e.second, e.first});
    if (c.face_patch[f] != c.face_patch[g]) {
      auto& nx = next[c.face_patch[f]];
      EXPECT_EQ(nx.count(e.first), 0u) << "patch " << c.patches[c.face_patch[f]].name << " is not a disk";
      nx[e.first] = e.second;
    }
  }
  for (int p = 0; p < np; ++p) {
    const auto& corners = c.patches[p].corners;
    std::vector<int> loop;
    for (int v = corners[0];;) {
      loop.push_back(v);
      ASSERT_TRUE(next[p].count(v)) << c.patches[p].name;
      v = next[p].at(v);
      if (v == corners[0] || loop.size() > next[p].size()) break;
    }
    EXPECT_EQ(loop.size(), next[p].size()) << "patch " << c.patches[p].name << " has more than one boundary loop";
    int last = -1;
    for (int i = 0; i < 4; ++i) {
      const int at = static_cast<int>(std::find(loop.begin(), loop.end(), corners[i]) - loop.begin());
      EXPECT_GT(at, last) << c.patches[p].name << " corner " << i;
      last = at;
    }
  }

  // Base domain: closed, conforming, Euler characteristic 2 (counted here from the corners).
  std::set<int> verts;
  std::map<std::pair<int, int>, int> sides;
  for (const auto& p : c.patches)
    for (int k = 0; k < 4; ++k) {
      verts.insert(p.corners[k]);
      ++sides[{p.corners[k], p.corners[(k + 1) % 4]}];
    }
  for (const auto& [s, n] : sides) {
    EXPECT_EQ(n, 1);
    EXPECT_EQ(sides.count({s.second, s.first}), 1u) << "side " << s.first << "-" << s.second << " has no twin";
  }
  EXPECT_EQ(static_cast<int>(verts.size()) - static_cast<int>(sides.size()) / 2 + np, 2);
  EXPECT_TRUE(d.base.closed_conforming);
  EXPECT_EQ(d.base.euler_characteristic, 2);
  EXPECT_EQ(d.base.quads.size(), c.patches.size());
}


}  // namespace qs::testing
