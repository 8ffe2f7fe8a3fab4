// The renderer: what ends up where in the image, depth-tested edges, uv layouts, PNG output, and
// the qs-render tool's exit codes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "qs/core/error.h"
#include "qs/render/render.h"
#include "../tools/tool_runner.h"
#include "qs/shapes/shapes.h"
#include "../common/test_support.h"

namespace fs = std::filesystem;
using qs::render::Image;
using qs::render::RenderOptions;
using qs::render::Rgb;
using ::testing::HasSubstr;

using qs::test::read_bytes;

namespace {

Rgb pixel(const Image& img, int x, int y) {
  const size_t i = 3 * (static_cast<size_t>(y) * img.width + x);
  return {img.rgb[i], img.rgb[i + 1], img.rgb[i + 2]};
}

bool is_white(const Rgb& c) { return c[0] == 255 && c[1] == 255 && c[2] == 255; }

class RenderFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("qs_render_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

RenderOptions front_view(int size = 200) {
  RenderOptions o;
  o.width = o.height = size;
  o.view_dir = qs::Vec3(0, 0, 1);
  return o;
}

}  // namespace

TEST(RenderMesh, SphereIsADiskInTheCentre) {
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  RenderOptions o;  // default oblique view
  o.width = o.height = 201;
  const Image img = qs::render::render_mesh(sphere, nullptr, o);
  ASSERT_EQ(img.width, 201);
  ASSERT_EQ(img.height, 201);
  ASSERT_EQ(img.rgb.size(), 3u * 201 * 201);
  // Fitted with a 5% margin: radius about 0.45 * 201 = 90 pixels.
  const double c = 100.5, r = 0.45 * 201;
  int inside_bg = 0, outside_fg = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double d = std::hypot(x + 0.5 - c, y + 0.5 - c);
      const bool bg = is_white(pixel(img, x, y));
      if (d < 0.95 * r && bg) ++inside_bg;
      if (d > 1.03 * r && !bg) ++outside_fg;
    }
  EXPECT_EQ(inside_bg, 0);
  EXPECT_EQ(outside_fg, 0);
  for (auto [x, y] : {std::array{0, 0}, {200, 0}, {0, 200}, {200, 200}}) EXPECT_TRUE(is_white(pixel(img, x, y)));
}

TEST(RenderMesh, HeadLightMakesTheCentreBrighterThanTheRim) {
  const Image img = qs::render::render_mesh(qs::shapes::icosphere(4), nullptr, front_view());
  const Rgb centre = pixel(img, 100, 100), rim = pixel(img, 100 + 85, 100);
  EXPECT_FALSE(is_white(rim));
  EXPECT_GT(centre[0], rim[0] + 60);
  EXPECT_EQ(centre[0], centre[1]);  // grey
}

TEST(RenderMesh, FaceColoursLandOnTheRightSideNotMirrored) {
  // +x faces red, -x faces blue, top (+y) faces green: seen from +z with y up, red is on the
  // right of the image and green at the top.
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  std::vector<Rgb> colours(sphere.num_faces());
  for (int f = 0; f < sphere.num_faces(); ++f) {
    qs::Vec3 c = qs::Vec3::Zero();
    for (int v : sphere.faces[f]) c += sphere.positions[v] / 3;
    colours[f] = c.y() > 0.6 ? Rgb{0, 255, 0} : (c.x() > 0 ? Rgb{255, 0, 0} : Rgb{0, 0, 255});
  }
  const Image img = qs::render::render_mesh(sphere, &colours, front_view());
  const Rgb right = pixel(img, 150, 110), left = pixel(img, 50, 110), top = pixel(img, 100, 30);
  EXPECT_GT(right[0], 100);
  EXPECT_EQ(right[2], 0);
  EXPECT_GT(left[2], 100);
  EXPECT_EQ(left[0], 0);
  EXPECT_GT(top[1], 100);
  EXPECT_EQ(top[0], 0);

  // Looking from -z instead, +x is on the left.
  RenderOptions back = front_view();
  back.view_dir = qs::Vec3(0, 0, -1);
  const Image b = qs::render::render_mesh(sphere, &colours, back);
  EXPECT_GT(pixel(b, 50, 110)[0], 100);
  EXPECT_GT(pixel(b, 150, 110)[2], 100);
}

TEST(RenderMesh, UpVectorTurnsTheImage) {
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  std::vector<Rgb> colours(sphere.num_faces(), Rgb{0, 0, 255});
  for (int f = 0; f < sphere.num_faces(); ++f)
    if (sphere.positions[sphere.faces[f][0]].x() > 0.6) colours[f] = {255, 0, 0};
  RenderOptions o = front_view();
  o.up = qs::Vec3(1, 0, 0);  // +x points up in the image
  const Image img = qs::render::render_mesh(sphere, &colours, o);
  EXPECT_GT(pixel(img, 100, 25)[0], 100);
  EXPECT_GT(pixel(img, 100, 175)[2], 100);
}

TEST(RenderMesh, SmoothShadingHasNoFacetSteps) {
  // Along a row of a coarse sphere, flat shading is piecewise constant; smooth shading changes
  // at (almost) every pixel.
  const qs::TriMesh sphere = qs::shapes::icosphere(1);
  RenderOptions o = front_view();
  const Image flat = qs::render::render_mesh(sphere, nullptr, o);
  o.smooth = true;
  const Image smooth = qs::render::render_mesh(sphere, nullptr, o);
  int flat_changes = 0, smooth_changes = 0;
  for (int x = 30; x < 170; ++x) {
    flat_changes += pixel(flat, x, 100)[0] != pixel(flat, x + 1, 100)[0];
    smooth_changes += pixel(smooth, x, 100)[0] != pixel(smooth, x + 1, 100)[0];
  }
  EXPECT_LT(flat_changes, 15);
  EXPECT_GT(smooth_changes, 40);
}

TEST(RenderMesh, HighlightEdgesAreDepthTested) {
  const qs::TriMesh sphere = qs::shapes::icosphere(3);
  std::vector<std::array<int, 2>> front, back;
  for (const auto& t : sphere.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      const qs::Vec3 &pa = sphere.positions[a], &pb = sphere.positions[b];
      if (pa.z() > 0.5 && pb.z() > 0.5 && a < b) front.push_back({a, b});
      if (pa.z() < -0.5 && pb.z() < -0.5 && a < b) back.push_back({a, b});
    }
  ASSERT_FALSE(front.empty());
  ASSERT_FALSE(back.empty());
  const RenderOptions o = front_view();
  const Image plain = qs::render::render_mesh(sphere, nullptr, o);
  const Image with_back = qs::render::render_mesh(sphere, nullptr, o, &back);
  EXPECT_EQ(plain.rgb, with_back.rgb) << "edges on the far side must be hidden";
  const Image with_front = qs::render::render_mesh(sphere, nullptr, o, &front);
  int dark = 0;
  for (int y = 0; y < 200; ++y)
    for (int x = 0; x < 200; ++x) dark += pixel(with_front, x, y) == Rgb{25, 25, 25};
  EXPECT_GT(dark, 1000);
}

TEST(RenderMesh, WireframeDarkensOnlyEdgePixels) {
  const qs::TriMesh sphere = qs::shapes::icosphere(2);
  RenderOptions o = front_view();
  const Image plain = qs::render::render_mesh(sphere, nullptr, o);
  o.wireframe = true;
  const Image wire = qs::render::render_mesh(sphere, nullptr, o);
  int darker = 0, changed = 0;
  for (size_t i = 0; i < plain.rgb.size(); i += 3) {
    changed += plain.rgb[i] != wire.rgb[i];
    darker += wire.rgb[i] < plain.rgb[i];
  }
  EXPECT_GT(changed, 1000);
  EXPECT_EQ(darker, changed);
  EXPECT_LT(changed, 200 * 200 / 2);
}

TEST(RenderMesh, IsDeterministic) {
  const qs::TriMesh mesh = qs::shapes::bumpy_sphere(0.3, 5, 4);
  RenderOptions o;
  o.width = 320;
  o.height = 240;
  o.smooth = true;
  o.wireframe = true;
  const Image a = qs::render::render_mesh(mesh, nullptr, o);
  const Image b = qs::render::render_mesh(mesh, nullptr, o);
  EXPECT_EQ(a.rgb, b.rgb);
}

TEST(RenderMesh, EmptyMeshIsBackground) {
  RenderOptions o = front_view(10);
  o.background = {1, 2, 3};
  const Image img = qs::render::render_mesh(qs::TriMesh{}, nullptr, o);
  for (int y = 0; y < 10; ++y)
    for (int x = 0; x < 10; ++x) EXPECT_EQ(pixel(img, x, y), (Rgb{1, 2, 3}));
}

TEST(RenderMesh, RejectsBadInput) {
  const qs::TriMesh sphere = qs::shapes::icosphere(0);
  std::vector<Rgb> few(3);
  EXPECT_THROW(qs::render::render_mesh(sphere, &few, front_view()), qs::InvalidInput);
  RenderOptions zero = front_view();
  zero.view_dir = qs::Vec3::Zero();
  EXPECT_THROW(qs::render::render_mesh(sphere, nullptr, zero), qs::InvalidInput);
  RenderOptions tiny = front_view();
  tiny.width = 0;
  EXPECT_THROW(qs::render::render_mesh(sphere, nullptr, tiny), qs::InvalidInput);
  qs::TriMesh broken = sphere;
  broken.faces[5][1] = 99;
  try {
    qs::render::render_mesh(broken, nullptr, front_view());
    FAIL() << "expected InvalidInput";
  } catch (const qs::InvalidInput& e) {
    EXPECT_THAT(e.what(), HasSubstr("face 5"));
  }
  std::vector<std::array<int, 2>> edges = {{0, 12}};
  EXPECT_THROW(qs::render::render_mesh(sphere, nullptr, front_view(), &edges), qs::InvalidInput);
}

// The picture depends on the shape only: a mesh moved far away and scaled to the largest
// doubles draws like the unit one (not black, not empty), while NaN is still refused.
TEST(RenderMesh, ExtremeButFiniteCoordinatesDrawTheSamePicture) {
  const qs::TriMesh unit = qs::shapes::icosphere(2);
  RenderOptions o = front_view(64);
  o.view_dir = qs::Vec3(0.3, 0.4, 1);
  o.wireframe = true;
  const Image reference = qs::render::render_mesh(unit, nullptr, o);
  // Scaled by a power of two: every normalized position is bitwise the same.
  qs::TriMesh pow2 = unit;
  for (auto& p : pow2.positions) p *= std::ldexp(1.0, 1022);
  EXPECT_EQ(qs::render::render_mesh(pow2, nullptr, o).rgb, reference.rgb);
  for (const double scale : {1e308, 1e-300}) {
    qs::TriMesh far = unit;
    for (auto& p : far.positions) p = scale * p + qs::Vec3(0.5 * scale, 0, 0);
    const Image img = qs::render::render_mesh(far, nullptr, o);
    int differ = 0, dark = 0;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) {
        differ += pixel(img, x, y) != pixel(reference, x, y);
        const Rgb c = pixel(reference, x, y);
        dark += c == pixel(img, x, y) ? 0 : pixel(img, x, y)[0] < 20;
      }
    EXPECT_LT(differ, 64 * 64 / 50) << scale;  // rounding on a few edge pixels at most
    EXPECT_EQ(dark, 0) << scale;
  }
  // A tetrahedron spanning the whole double range (its differences overflow): shaded grey, like
  // the unit one.
  qs::TriMesh small;
  small.positions = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, -1, -1}};
  small.faces = {{0, 1, 2}, {0, 3, 1}, {1, 3, 2}, {2, 3, 0}};
  qs::TriMesh tet = small;
  for (auto& p : tet.positions) p *= std::ldexp(1.0, 1023);
  const Image small_img = qs::render::render_mesh(small, nullptr, front_view(64));
  EXPECT_EQ(qs::render::render_mesh(tet, nullptr, front_view(64)).rgb, small_img.rgb);
  for (auto& p : tet.positions) p = p / std::ldexp(1.0, 1023) * 1.79e308;
  const Image big_img = qs::render::render_mesh(tet, nullptr, front_view(64));
  int differ = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) differ += pixel(big_img, x, y) != pixel(small_img, x, y);
  EXPECT_LT(differ, 64 * 64 / 50);
  EXPECT_NE(pixel(big_img, 32, 32), (Rgb{0, 0, 0}));
  qs::TriMesh nan = tet;
  nan.positions[2].y() = std::nan("");
  EXPECT_THROW(qs::render::render_mesh(nan, nullptr, front_view(64)), qs::InvalidInput);
}

TEST(RenderMesh, UpParallelToViewStillRenders) {
  RenderOptions o = front_view(50);
  o.up = qs::Vec3(0, 0, 5);
  const Image img = qs::render::render_mesh(qs::shapes::icosphere(2), nullptr, o);
  EXPECT_FALSE(is_white(pixel(img, 25, 25)));
}

namespace {

// Two patches, each the unit square in two triangles.
struct TwoPatchChart {
  std::vector<std::array<qs::Vec2, 3>> uv;
  std::vector<int> patch;
  std::vector<Rgb> colours = {Rgb{230, 120, 40}, Rgb{60, 140, 220}};
  TwoPatchChart() {
    const qs::Vec2 a(0, 0), b(1, 0), c(1, 1), d(0, 1);
    for (int p = 0; p < 2; ++p) {
      uv.push_back({a, b, c});
      uv.push_back({a, c, d});
      patch.push_back(p);
      patch.push_back(p);
    }
  }
};

}  // namespace

TEST(RenderUvLayout, EachPatchInItsOwnTile) {
  const TwoPatchChart chart;
  const Image img = qs::render::render_uv_layout(chart.uv, chart.patch, 2, 64, chart.colours);
  ASSERT_EQ(img.width, 128);  // ceil(sqrt(2)) = 2 columns
  ASSERT_EQ(img.height, 64);
  EXPECT_EQ(pixel(img, 20, 40), chart.colours[0]);
  EXPECT_EQ(pixel(img, 64 + 20, 40), chart.colours[1]);
  // The gap around the unit square stays white; no pixel is red (bijective).
  EXPECT_TRUE(is_white(pixel(img, 0, 0)));
  EXPECT_TRUE(is_white(pixel(img, 64, 63)));
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x) ASSERT_NE(pixel(img, x, y), (Rgb{255, 0, 0})) << x << "," << y;
}

TEST(RenderUvLayout, FlippedAndOverlappingTrianglesAreRed) {
  TwoPatchChart chart;
  std::swap(chart.uv[0][1], chart.uv[0][2]);  // patch 0: one triangle flipped
  chart.uv[3] = {qs::Vec2(0, 0), qs::Vec2(1, 0), qs::Vec2(0.5, 1)};  // patch 1: overlaps uv[2]
  const Image img = qs::render::render_uv_layout(chart.uv, chart.patch, 2, 64, chart.colours);
  int red0 = 0, red1 = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 128; ++x)
      if (pixel(img, x, y) == Rgb{255, 0, 0}) ++(x < 64 ? red0 : red1);
  EXPECT_GT(red0, 300);
  EXPECT_GT(red1, 300);
}

TEST(RenderUvLayout, GridOfManyPatches) {
  std::vector<std::array<qs::Vec2, 3>> uv;
  std::vector<int> patch;
  std::vector<Rgb> colours;
  for (int p = 0; p < 5; ++p) {
    uv.push_back({qs::Vec2(0, 0), qs::Vec2(1, 0), qs::Vec2(0, 1)});
    patch.push_back(p);
    colours.push_back({static_cast<std::uint8_t>(40 * p), 200, 100});
  }
  const Image img = qs::render::render_uv_layout(uv, patch, 5, 32, colours);
  EXPECT_EQ(img.width, 96);  // 3 columns, 2 rows
  EXPECT_EQ(img.height, 64);
  EXPECT_EQ(pixel(img, 32 + 8, 24), colours[1]);  // lower left of tile 1 (row 0, column 1)
  EXPECT_EQ(pixel(img, 32 + 8, 32 + 24), colours[4]);  // tile 4: row 1, column 1
}

TEST(RenderUvLayout, RejectsBadInput) {
  const TwoPatchChart chart;
  EXPECT_THROW(qs::render::render_uv_layout(chart.uv, {0, 0, 1}, 2, 64, chart.colours), qs::InvalidInput);
  EXPECT_THROW(qs::render::render_uv_layout(chart.uv, {0, 0, 1, 2}, 2, 64, chart.colours), qs::InvalidInput);
  EXPECT_THROW(qs::render::render_uv_layout(chart.uv, chart.patch, 2, 4, chart.colours), qs::InvalidInput);
  EXPECT_THROW(qs::render::render_uv_layout(chart.uv, chart.patch, 2, 64, {}), qs::InvalidInput);
}

TEST(SideBySide, ConcatenatesAndPads) {
  Image a{2, 2, std::vector<std::uint8_t>(12, 0)};
  Image b{3, 4, std::vector<std::uint8_t>(36, 7)};
  const Image c = qs::render::side_by_side({a, b});
  ASSERT_EQ(c.width, 5);
  ASSERT_EQ(c.height, 4);
  EXPECT_TRUE(is_white(pixel(c, 0, 0)));
  EXPECT_EQ(pixel(c, 0, 1), (Rgb{0, 0, 0}));
  EXPECT_EQ(pixel(c, 1, 2), (Rgb{0, 0, 0}));
  EXPECT_TRUE(is_white(pixel(c, 1, 3)));
  EXPECT_EQ(pixel(c, 4, 0), (Rgb{7, 7, 7}));
  Image bad{3, 3, std::vector<std::uint8_t>(5, 0)};
  EXPECT_THROW(qs::render::side_by_side({a, bad}), qs::InvalidInput);
}

TEST_F(RenderFiles, WritePngIsAtomicAndDeterministic) {
  const Image img = qs::render::render_mesh(qs::shapes::icosphere(2), nullptr, front_view(64));
  const fs::path p1 = dir_ / "a.png", p2 = dir_ / "b.png";
  qs::render::write_png(p1, img);
  qs::render::write_png(p2, qs::render::render_mesh(qs::shapes::icosphere(2), nullptr, front_view(64)));
  const std::string bytes = read_bytes(p1);
  ASSERT_GT(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  EXPECT_EQ(bytes, read_bytes(p2));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 2) << "no temporary left";
}

TEST_F(RenderFiles, WritePngToAnUnwritablePlaceThrowsIoError) {
  const Image img = qs::render::render_mesh(qs::shapes::icosphere(1), nullptr, front_view(16));
  try {
    qs::render::write_png(dir_ / "no" / "such" / "dir" / "x.png", img);
    FAIL() << "expected IoError";
  } catch (const qs::IoError& e) {
    EXPECT_THAT(e.what(), HasSubstr("x.png"));
  }
  // A directory in the way of the final name: the rename fails, the temporary is removed.
  fs::create_directories(dir_ / "taken.png" / "inside");
  EXPECT_THROW(qs::render::write_png(dir_ / "taken.png", img), qs::IoError);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
  EXPECT_THROW(qs::render::write_png(dir_ / "empty.png", Image{}), qs::InvalidInput);
}

// ---- the qs-render tool ---------------------------------------------------------------------

namespace {

RunResult run_tool(const std::string& args) { return ::run_tool("qs-render", args); }

std::string off_text(const qs::TriMesh& m) {
  std::ostringstream s;
  s << "OFF\n" << m.num_vertices() << " " << m.num_faces() << " 0\n";
  for (const auto& p : m.positions) s << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& t : m.faces) s << "3 " << t[0] << " " << t[1] << " " << t[2] << "\n";
  return s.str();
}

}  // namespace

class RenderTool : public RenderFiles {
 protected:
  std::string sphere() {
    const fs::path p = dir_ / "sphere.off";
    std::ofstream(p) << off_text(qs::shapes::icosphere(2));
    return p.string();
  }
};

TEST_F(RenderTool, RendersSideBySide) {
  const std::string s = sphere(), out = (dir_ / "out.png").string();
  const RunResult r = run_tool(s + " " + s + " -o " + out + " --size 120x100 --wireframe --smooth --view 1,0,0");
  ASSERT_EQ(r.exit, 0) << r.out;
  const std::string bytes = read_bytes(out);
  ASSERT_GT(bytes.size(), 24u);
  // PNG IHDR: width and height, big-endian, at bytes 16..23.
  auto be32 = [&](int at) {
    return (static_cast<unsigned char>(bytes[at]) << 24) | (static_cast<unsigned char>(bytes[at + 1]) << 16) |
           (static_cast<unsigned char>(bytes[at + 2]) << 8) | static_cast<unsigned char>(bytes[at + 3]);
  };
  EXPECT_EQ(be32(16), 240);
  EXPECT_EQ(be32(20), 100);
}

TEST_F(RenderTool, OneViewPerInput) {
  const std::string s = sphere(), a = (dir_ / "a.png").string(), b = (dir_ / "b.png").string();
  // Both inputs seen from +x, written once with one view and once with a view per input: the same
  // image; a different second view changes it.
  ASSERT_EQ(run_tool(s + " " + s + " -o " + a + " --size 64 --view 1,0,0").exit, 0);
  ASSERT_EQ(run_tool(s + " " + s + " -o " + b + " --size 64 --view 1,0,0,1,0,0").exit, 0);
  EXPECT_EQ(read_bytes(a), read_bytes(b));
  ASSERT_EQ(run_tool(s + " " + s + " -o " + b + " --size 64 --view 1,0,0,0,1,0.2").exit, 0);
  EXPECT_NE(read_bytes(a), read_bytes(b));
  const RunResult r = run_tool(s + " " + s + " -o " + b + " --view 1,0,0,1");
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("one x,y,z per input"));
}

TEST_F(RenderTool, ErrorsGiveDocumentedExitCodesAndNoOutput) {
  const std::string s = sphere(), out = (dir_ / "out.png").string();
  RunResult r = run_tool((dir_ / "missing.obj").string() + " -o " + out);
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_THAT(r.out, HasSubstr("missing.obj"));
  r = run_tool(s + " " + (dir_ / "missing.obj").string() + " -o " + out);  // fails after the first
  EXPECT_EQ(r.exit, 3) << r.out;
  std::ofstream(dir_ / "mesh.xyz") << "not a mesh";
  r = run_tool((dir_ / "mesh.xyz").string() + " -o " + out);
  EXPECT_EQ(r.exit, 2) << r.out;
  std::ofstream(dir_ / "garbage.off") << "OFF\n3 1 0\n0 0 0\n1 0\n";
  r = run_tool((dir_ / "garbage.off").string() + " -o " + out);
  EXPECT_EQ(r.exit, 2) << r.out;
  r = run_tool(s + " -o " + (dir_ / "out.jpg").string());
  EXPECT_EQ(r.exit, 1) << r.out;
  r = run_tool(s + " -o " + out + " --uv");
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("chart"));
  r = run_tool(s + " -o " + out + " --size 12x");
  EXPECT_EQ(r.exit, 1) << r.out;
  r = run_tool(s + " -o " + out + " --view 0,0");
  EXPECT_EQ(r.exit, 1) << r.out;
  r = run_tool(s + " -o " + (dir_ / "nodir" / "out.png").string());
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_FALSE(fs::exists(out));
  // Only the inputs are left: no output, no temporaries.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 3);
}

TEST_F(RenderTool, ExtremeCoordinatesRenderLikeTheUnitShape) {
  const std::string mesh = (dir_ / "tet.obj").string(), unit = (dir_ / "unit.obj").string();
  // 2^1023 (differences of these overflow), so that the picture must be bitwise the unit one's.
  const std::string m = "8.9884656743115795e307";
  std::ofstream(mesh) << "v " << m << " 0 0\nv 0 " << m << " 0\nv 0 0 " << m << "\nv -" << m << " -" << m << " -"
                      << m << "\nf 1 2 3\nf 1 4 2\nf 2 4 3\nf 3 4 1\n";
  std::ofstream(unit) << "v 1 0 0\nv 0 1 0\nv 0 0 1\nv -1 -1 -1\nf 1 2 3\nf 1 4 2\nf 2 4 3\nf 3 4 1\n";
  const std::string a = (dir_ / "a.png").string(), b = (dir_ / "b.png").string();
  RunResult r = run_tool(mesh + " -q --size 48 -o " + a);
  ASSERT_EQ(r.exit, 0) << r.out;
  r = run_tool(unit + " -q --size 48 -o " + b);
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(read_bytes(a), read_bytes(b));
}

// The estimate covers the measured peak (an 8192 x 8192 view of a small mesh: 1.12 GiB resident)
// and the refusal comes before any reading or drawing, with the figure.
TEST_F(RenderTool, RefusesAPictureOverMaxMemoryUpFrontWithTheEstimate) {
  const std::string s = sphere(), out = (dir_ / "big.png").string();
  // CPU time of the tool (not wall time, which depends on the machine's load).
  const auto child_cpu = [] {
    rusage u{};
    getrusage(RUSAGE_CHILDREN, &u);
    return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
  };
  const double cpu0 = child_cpu();
  RunResult r = run_tool(s + " --size 8192 --max-memory 0.7 -o " + out);
  const double cpu = child_cpu() - cpu0;
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("1 view of 8192 x 8192 needs about 1.53 GiB of memory, more than --max-memory 0.7 GiB"));
  EXPECT_LT(cpu, 2.0);  // no drawing: that takes about 9 s of CPU at this size
  EXPECT_FALSE(fs::exists(out));
  // Several views count each kept view and the joined picture.
  r = run_tool(s + " " + s + " --size 4096x8192 --max-memory 0.9 -o " + out);
  EXPECT_EQ(r.exit, 1) << r.out;
  EXPECT_THAT(r.out, HasSubstr("2 views of 4096 x 8192 needs about 1.03 GiB"));
  for (const char* bad : {"nan", "inf", "-1", "0"}) {
    r = run_tool(s + " --max-memory " + bad + " -o " + out);
    EXPECT_EQ(r.exit, 1) << bad << ": " << r.out;
    EXPECT_THAT(r.out, HasSubstr("--max-memory")) << bad;
  }
  EXPECT_FALSE(fs::exists(out));
}
