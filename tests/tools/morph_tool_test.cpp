// qs-morph as a user runs it: a remeshed triple (qs-dissect + qs-remesh), frames, blends, GLBs
// (checked with the Khronos validator when it is installed), a bake folder, and every bad argument.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"
#include "qs/shapes/shapes.h"
#include "../common/image_test_support.h"
#include "../common/test_support.h"
#include "tool_runner.h"
#include "../common/gltf_test_support.h"

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using qs::test::read_bytes;

namespace {

int count_frames(const fs::path& dir) {
  int n = 0;
  if (!fs::exists(dir)) return 0;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().rfind("frame_", 0) == 0) ++n;
  return n;
}

// The JSON chunk of a GLB.
nlohmann::json glb_json(const fs::path& p) {
  const std::string b = read_bytes(p);
  if (b.size() < 20 || b.compare(0, 4, "glTF") != 0) return {};
  uint32_t len;
  std::memcpy(&len, b.data() + 12, 4);
  return nlohmann::json::parse(b.substr(20, len));
}

int validate(const fs::path& file, std::string* out) { return qs::testing::run_gltf_validator(file, out); }

// ---- a bake folder written by hand (independent of qs's own GLB writer) ----------------------
uint32_t crc32(const std::string& s) {
  uint32_t c = 0xFFFFFFFFu;
  for (unsigned char ch : s) {
    c ^= ch;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return c ^ 0xFFFFFFFFu;
}
void be32(std::string& s, uint32_t x) {
  for (int k = 24; k >= 0; k -= 8) s += static_cast<char>(x >> k);
}
std::string flat_normal_png(int w, int h) {
  std::string raw;
  for (int y = 0; y < h; ++y) {
    raw += '\0';
    for (int x = 0; x < w; ++x) raw += std::string{char(128), char(128), char(255)};
  }
  const uint16_t n = static_cast<uint16_t>(raw.size());
  std::string z{char(0x78), char(0x01), char(1), char(n & 0xFF), char(n >> 8), char(~n & 0xFF), char((~n >> 8) & 0xFF)};
  z += raw;
  uint32_t a = 1, b = 0;
  for (unsigned char c : raw) {
    a = (a + c) % 65521;
    b = (b + a) % 65521;
  }
  be32(z, (b << 16) | a);
  std::string png = "\x89PNG\r\n\x1a\n";
  auto chunk = [&](const std::string& type, const std::string& data) {
    be32(png, static_cast<uint32_t>(data.size()));
    png += type + data;
    be32(png, crc32(type + data));
  };
  std::string ihdr;
  be32(ihdr, w);
  be32(ihdr, h);
  ihdr += std::string{8, 2, 0, 0, 0};
  chunk("IHDR", ihdr);
  chunk("IDAT", z);
  chunk("IEND", "");
  return png;
}

// <dir>/<stem>.glb: `mesh` with unit normals (its normalized positions), spherical UVs, tangents,
// the normal map in the material; and <dir>/bake.json.
void write_bake(const fs::path& dir, const std::string& stem, const qs::TriMesh& mesh) {
  fs::create_directories(dir);
  std::ofstream(dir / "bake.json") << R"({"format": "qs-bake", "version": 1})";
  std::string bin;
  nlohmann::json views = nlohmann::json::array(), accessors = nlohmann::json::array();
  auto view = [&](const std::string& data) {
    while (bin.size() % 4) bin += '\0';
    views.push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", data.size()}});
    bin += data;
    return views.size() - 1;
  };
  auto floats = [&](const std::vector<float>& f, const char* type, bool bounds) {
    std::string d(f.size() * 4, '\0');
    std::memcpy(d.data(), f.data(), d.size());
    const int comps = std::string(type) == "VEC2" ? 2 : std::string(type) == "VEC3" ? 3 : 4;
    nlohmann::json a = {{"bufferView", view(d)}, {"componentType", 5126}, {"count", f.size() / comps}, {"type", type}};
    if (bounds) {
      std::vector<float> lo(comps, 1e30f), hi(comps, -1e30f);
      for (size_t i = 0; i < f.size(); ++i) {
        lo[i % comps] = std::min(lo[i % comps], f[i]);
        hi[i % comps] = std::max(hi[i % comps], f[i]);
      }
      a["min"] = lo;
      a["max"] = hi;
    }
    accessors.push_back(a);
    return accessors.size() - 1;
  };
  std::vector<float> pos, nrm, uv, tan;
  for (const qs::Vec3& p : mesh.positions) {
    const qs::Vec3 n = p.normalized();
    const qs::Vec3 axis = std::abs(n.z()) < 0.9 ? qs::Vec3(0, 0, 1) : qs::Vec3(1, 0, 0);
    const qs::Vec3 t = axis.cross(n).normalized();
    for (int c = 0; c < 3; ++c) {
      pos.push_back(static_cast<float>(p[c]));
      nrm.push_back(static_cast<float>(n[c]));
      tan.push_back(static_cast<float>(t[c]));
    }
    tan.push_back(1.0f);
    uv.push_back(static_cast<float>(0.5 + 0.5 * std::atan2(n.y(), n.x()) / M_PI));
    uv.push_back(static_cast<float>(0.5 - 0.5 * n.z()));
  }
  const auto p_acc = floats(pos, "VEC3", true), n_acc = floats(nrm, "VEC3", false), uv_acc = floats(uv, "VEC2", false),
             t_acc = floats(tan, "VEC4", false);
  std::vector<uint32_t> idx;
  for (const auto& f : mesh.faces)
    for (int v : f) idx.push_back(static_cast<uint32_t>(v));
  std::string id(idx.size() * 4, '\0');
  std::memcpy(id.data(), idx.data(), id.size());
  accessors.push_back({{"bufferView", view(id)}, {"componentType", 5125}, {"count", idx.size()}, {"type", "SCALAR"}});
  const auto i_acc = accessors.size() - 1;
  const auto img_view = view(flat_normal_png(8, 8));
  while (bin.size() % 4) bin += '\0';
  const nlohmann::json doc = {
      {"asset", {{"version", "2.0"}, {"generator", "hand-made bake"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}}}},
      {"meshes",
       {{{"primitives",
          {{{"attributes", {{"POSITION", p_acc}, {"NORMAL", n_acc}, {"TEXCOORD_0", uv_acc}, {"TANGENT", t_acc}}},
            {"indices", i_acc},
            {"material", 0}}}}}}},
      {"materials", {{{"normalTexture", {{"index", 0}}}}}},
      {"textures", {{{"source", 0}}}},
      {"images", {{{"bufferView", img_view}, {"mimeType", "image/png"}}}},
      {"accessors", accessors},
      {"bufferViews", views},
      {"buffers", {{{"byteLength", bin.size()}}}}};
  std::string json = doc.dump();
  while (json.size() % 4) json += ' ';
  std::string glb = "glTF";
  auto le32 = [&](uint32_t x) {
    for (int k = 0; k < 4; ++k) glb += static_cast<char>(x >> (8 * k));
  };
  le32(2);
  le32(static_cast<uint32_t>(12 + 8 + json.size() + 8 + bin.size()));
  le32(static_cast<uint32_t>(json.size()));
  le32(0x4E4F534A);
  glb += json;
  le32(static_cast<uint32_t>(bin.size()));
  le32(0x004E4942);
  glb += bin;
  std::ofstream(dir / (stem + ".glb"), std::ios::binary) << glb;
  std::ofstream(dir / (stem + "_normal.png"), std::ios::binary) << flat_normal_png(8, 8);
}

class MorphTool : public ::testing::Test {
 protected:
  // One remeshed triple a, b, c for the whole suite (dissecting is the slow part).
  static void SetUpTestSuite() {
    root_ = fs::temp_directory_path() / ("qs_morph_tool_" + std::to_string(::getpid()));
    fs::create_directories(root_);
    qs::io::write_mesh(root_ / "a.obj", qs::shapes::ellipsoid(1.4, 1, 0.8, 3));
    qs::io::write_mesh(root_ / "b.obj", qs::shapes::bumpy_sphere(0.05, 3, 3));
    qs::io::write_mesh(root_ / "c.obj", qs::shapes::ellipsoid(0.9, 1.3, 1, 3));
    const RunResult d = run_tool("qs-dissect", (root_ / "a.obj").string() + " " + (root_ / "b.obj").string() + " " +
                                                   (root_ / "c.obj").string() + " -q -o " + (root_ / "D").string());
    ASSERT_EQ(d.exit, 0) << d.out;
    const RunResult r = run_tool("qs-remesh", (root_ / "D").string() + " --level 2 -q -o " + (root_ / "R").string());
    ASSERT_EQ(r.exit, 0) << r.out;
  }
  static void TearDownTestSuite() { fs::remove_all(root_); }
  void SetUp() override {
    dir_ = root_ / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::create_directories(dir_);
  }
  static std::vector<qs::Vec3> shape(const std::string& stem) { return qs::io::read_mesh(R() / (stem + ".obj")).mesh.positions; }
  static fs::path R() { return root_ / "R"; }
  static RunResult morph(const std::string& args) { return run_tool("qs-morph", R().string() + " " + args); }
  static fs::path root_;
  fs::path dir_;
};
fs::path MorphTool::root_;

}  // namespace

TEST_F(MorphTool, DefaultPathFramesStartAndEndOnTheShapesExactly) {
  const RunResult r = morph("-o " + dir_.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("wrote 21 frames along a -> b -> c"));
  EXPECT_EQ(count_frames(dir_), 21);  // 10 per leg + 1
  const auto a = qs::io::read_mesh(R() / "a.obj").mesh;
  const auto f0 = qs::io::read_mesh(dir_ / "frame_0000.obj").mesh;
  EXPECT_EQ(f0.positions, a.positions);  // bit-exact
  EXPECT_EQ(f0.faces, a.faces);
  EXPECT_EQ(qs::io::read_mesh(dir_ / "frame_0010.obj").mesh.positions, shape("b"));
  EXPECT_EQ(qs::io::read_mesh(dir_ / "frame_0020.obj").mesh.positions, shape("c"));
  EXPECT_EQ(read_bytes(dir_ / "frame_0000.obj"), read_bytes(R() / "a.obj")) << "the same text as qs-remesh writes";
  std::ifstream in(dir_ / "morph.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["format"], "qs-morph");
  EXPECT_EQ(j["path"], (nlohmann::json{"a", "b", "c"}));
  EXPECT_EQ(j["shapes"], (nlohmann::json{"a", "b", "c"}));
  EXPECT_EQ(j["frames"]["count"], 21);
  EXPECT_EQ(j["frames"]["list"][10]["file"], "frame_0010.obj");
  EXPECT_EQ(j["frames"]["list"][10]["weights"], (nlohmann::json{0.0, 1.0, 0.0}));
  EXPECT_EQ(j["frames"]["list"][15]["weights"], (nlohmann::json{0.0, 0.5, 0.5}));
  EXPECT_FALSE(j.contains("blend"));
  // Deterministic: a second run writes the same bytes.
  const fs::path again = dir_ / "again";
  ASSERT_EQ(morph("-q --threads 1 -o " + again.string()).exit, 0);
  EXPECT_EQ(read_bytes(again / "frame_0007.obj"), read_bytes(dir_ / "frame_0007.obj"));
  EXPECT_EQ(read_bytes(again / "morph.json"), read_bytes(dir_ / "morph.json"));
}

TEST_F(MorphTool, MidpointOfATwoShapePathIsTheAverage) {
  const RunResult r = morph("--path a,c --frames 3 --format ply -q -o " + dir_.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(r.out, "");  // -q
  EXPECT_EQ(count_frames(dir_), 3);
  const auto a = shape("a"), c = shape("c");
  EXPECT_EQ(qs::io::read_mesh(dir_ / "frame_0000.ply").mesh.positions, a);
  EXPECT_EQ(qs::io::read_mesh(dir_ / "frame_0002.ply").mesh.positions, c);
  const auto mid = qs::io::read_mesh(dir_ / "frame_0001.ply").mesh.positions;
  ASSERT_EQ(mid.size(), a.size());
  for (size_t v = 0; v < a.size(); ++v) {
    const qs::Vec3 avg = (a[v] + c[v]) / 2;
    EXPECT_LE((mid[v] - avg).cwiseAbs().maxCoeff(), 4e-16 * std::max(1.0, avg.cwiseAbs().maxCoeff()));
  }
}

TEST_F(MorphTool, RepeatedPathReturnsToTheStart) {
  const RunResult r = morph("--path b,a,b --frames 6 -q -o " + dir_.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(qs::io::read_mesh(dir_ / "frame_0005.obj").mesh.positions, shape("b"));
  EXPECT_EQ(qs::io::read_mesh(dir_ / "frame_0000.obj").mesh.positions, shape("b"));
}

TEST_F(MorphTool, AlignPlacesEveryShapeOnTheFirstOfThePath) {
  const RunResult r = morph("--path a,c --frames 2 --align similarity -q -o " + dir_.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  const auto a = shape("a"), c = shape("c");
  EXPECT_EQ(qs::io::read_mesh(dir_ / "frame_0000.obj").mesh.positions, a) << "the base does not move";
  const auto last = qs::io::read_mesh(dir_ / "frame_0001.obj").mesh.positions;
  ASSERT_EQ(last.size(), c.size());
  // The aligned shape is c moved by a similarity: pairwise distances scale by one factor.
  const double k = (last[1] - last[0]).norm() / (c[1] - c[0]).norm();
  for (size_t v = 2; v < c.size(); v += 7) EXPECT_NEAR((last[v] - last[0]).norm(), k * (c[v] - c[0]).norm(), 1e-9);
  std::ifstream in(dir_ / "morph.json");
  EXPECT_EQ(nlohmann::json::parse(in)["options"]["align"], "similarity");
  EXPECT_EQ(morph("--align affine -o " + (dir_ / "x").string()).exit, 1);
}

TEST_F(MorphTool, WeightsWriteOneBlend) {
  const RunResult r = morph("--weights 0.2,0.3,0.5 -q -o " + dir_.string());
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_EQ(count_frames(dir_), 0) << "--weights alone writes no frames";
  const auto a = shape("a"), b = shape("b"), c = shape("c");
  const auto blend = qs::io::read_mesh(dir_ / "blend.obj").mesh.positions;
  ASSERT_EQ(blend.size(), a.size());
  for (size_t v = 0; v < a.size(); ++v) EXPECT_LT((blend[v] - (0.2 * a[v] + 0.3 * b[v] + 0.5 * c[v])).norm(), 1e-14);
  std::ifstream in(dir_ / "morph.json");
  EXPECT_EQ(nlohmann::json::parse(in)["blend"]["weights"], (nlohmann::json{0.2, 0.3, 0.5}));
}

TEST_F(MorphTool, GlbHasTargetsAnimationAndValidates) {
  const fs::path glb = dir_ / "new" / "m.glb";  // the folder is created
  const RunResult r = morph("--path b,c,a --glb " + glb.string() + " --weights 0.5,0.25,0.25");
  ASSERT_EQ(r.exit, 0) << r.out;
  EXPECT_THAT(r.out, HasSubstr("base b, 2 morph targets"));
  const auto j = glb_json(glb);
  ASSERT_TRUE(j.is_object());
  const auto& mesh = j["meshes"][0];
  EXPECT_EQ(mesh["extras"]["targetNames"], (nlohmann::json{"a", "c"}));
  EXPECT_EQ(mesh["weights"], (nlohmann::json{0.5, 0.25}));
  ASSERT_EQ(mesh["primitives"][0]["targets"].size(), 2u);
  for (const auto& t : mesh["primitives"][0]["targets"]) {
    EXPECT_TRUE(j["accessors"][t["POSITION"].get<int>()].contains("min"));
    EXPECT_TRUE(t.contains("NORMAL"));
  }
  ASSERT_EQ(j["animations"].size(), 1u);
  EXPECT_EQ(j["animations"][0]["channels"][0]["target"]["path"], "weights");
  EXPECT_EQ(j["accessors"][j["animations"][0]["samplers"][0]["input"].get<int>()]["count"], 3);
  EXPECT_EQ(j["accessors"][j["animations"][0]["samplers"][0]["input"].get<int>()]["max"], (nlohmann::json{2.0}));
  std::string out;
  const int rc = validate(glb, &out);
  if (rc == 3) GTEST_SKIP() << "glTF validator not installed (scripts/setup.sh): " << out;
  EXPECT_EQ(rc, 0) << out;
  EXPECT_THAT(out, HasSubstr(": 0 errors, 0 warnings")) << out;
}

TEST_F(MorphTool, BakeFolderPutsTheNormalMapIntoTheGlb) {
  write_bake(dir_ / "bake", "c", qs::io::read_mesh(R() / "c.obj").mesh);
  const fs::path glb = dir_ / "baked.glb";
  const RunResult r = morph("--path c,a --glb " + glb.string() + " --bake " + (dir_ / "bake").string() + " -q");
  ASSERT_EQ(r.exit, 0) << r.out;
  const auto j = glb_json(glb);
  ASSERT_TRUE(j.is_object());
  const auto& prim = j["meshes"][0]["primitives"][0];
  EXPECT_TRUE(prim["attributes"].contains("TEXCOORD_0"));
  EXPECT_TRUE(prim["attributes"].contains("TANGENT"));
  ASSERT_TRUE(prim.contains("material"));
  EXPECT_TRUE(j["materials"][prim["material"].get<int>()].contains("normalTexture"));
  EXPECT_EQ(j["images"][0]["mimeType"], "image/png");
  std::string out;
  const int rc = validate(glb, &out);
  if (rc == 3) GTEST_SKIP() << "glTF validator not installed (scripts/setup.sh): " << out;
  EXPECT_EQ(rc, 0) << out;
  EXPECT_THAT(out, HasSubstr(": 0 errors, 0 warnings")) << out;
}

TEST_F(MorphTool, BadArgumentsGiveTheDocumentedExitCodes) {
  struct Case {
    std::string args;
    int exit;
    std::string message;
  };
  const std::string o = " -o " + (dir_ / "out").string();
  const std::string bake = (dir_ / "bake").string();
  fs::create_directories(dir_ / "bake");  // no bake.json
  const Case cases[] = {
      {"--weights 0.5,0.5" + o, 2, "2 given, expected one per shape (3)"},
      {"--weights 0.5,0.5" + o, 2, "in order: a, b, c"},
      {"--weights -0.2,0.6,0.6" + o, 2, "weight 1 is -0.2; every weight must be >= 0"},
      {"--weights 0.2,0.2,0.2" + o, 2, "sum to 0.6"},
      {"--weights x,y,z" + o, 1, "--weights"},
      {"--path a,cow" + o, 2, "unknown shape 'cow'; the shapes are: a, b, c"},
      {"--path a" + o, 2, "--path needs at least 2 shapes"},
      {"--frames 1" + o, 1, "--frames"},
      {"--format stl" + o, 1, "--format"},
      {"--bake " + bake + o, 1, "--bake needs --glb"},
      {"--glb " + (dir_ / "x.glb").string() + " --bake " + bake, 3, "bake.json: cannot open"},
      {"--no-such-option", 1, "no-such-option"},
  };
  for (const Case& c : cases) {
    const RunResult r = morph(c.args);
    EXPECT_EQ(r.exit, c.exit) << c.args << "\n" << r.out;
    EXPECT_THAT(r.out, HasSubstr(c.message)) << c.args;
    EXPECT_FALSE(fs::exists(dir_ / "out")) << c.args << ": nothing may be written on failure";
    EXPECT_FALSE(fs::exists(dir_ / "x.glb")) << c.args;
  }
  // A bake folder with bake.json but without the base shape's GLB; then one of another shape.
  std::ofstream(dir_ / "bake" / "bake.json") << "{}";
  RunResult r = morph("--glb " + (dir_ / "x.glb").string() + " --bake " + bake);
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_THAT(r.out, HasSubstr("a.glb: no such file"));
  write_bake(dir_ / "bake", "a", qs::io::read_mesh(R() / "b.obj").mesh);
  r = morph("--glb " + (dir_ / "x.glb").string() + " --bake " + bake);
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("was it baked from this remesh?"));
  EXPECT_FALSE(fs::exists(dir_ / "x.glb"));

  const RunResult missing = run_tool("qs-morph", (dir_ / "nothing").string());
  EXPECT_EQ(missing.exit, 3) << missing.out;
  EXPECT_THAT(missing.out, HasSubstr("remesh.json"));
  std::ofstream(dir_ / "afile") << "x";
  const RunResult blocked = morph("-o " + (dir_ / "afile" / "sub").string());
  EXPECT_EQ(blocked.exit, 3) << blocked.out;
  EXPECT_THAT(blocked.out, HasSubstr("cannot create the folder"));
}

TEST_F(MorphTool, MeshesThatDoNotShareAConnectivityAreRefused) {
  const fs::path copy = dir_ / "R";
  fs::copy(R(), copy);
  // Edit one face of b.obj: its first "f" line gets its corners rotated the other way.
  std::istringstream in(read_bytes(copy / "b.obj"));
  std::string line, out;
  bool edited = false;
  while (std::getline(in, line)) {
    if (!edited && line.rfind("f ", 0) == 0) {
      std::istringstream f(line.substr(2));
      std::string x, y, z;
      f >> x >> y >> z;
      line = "f " + x + " " + z + " " + y;
      edited = true;
    }
    out += line + "\n";
  }
  ASSERT_TRUE(edited);
  std::ofstream(copy / "b.obj") << out;
  const RunResult r = run_tool("qs-morph", copy.string() + " -o " + (dir_ / "out").string());
  EXPECT_EQ(r.exit, 2) << r.out;
  EXPECT_THAT(r.out, HasSubstr("b.obj"));
  EXPECT_THAT(r.out, HasSubstr("faces differ"));
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

// A damaged normal map: exit 2 (invalid input), one message in qs's words that names the file
// and what was expected, none of the image library's text, nothing written.
TEST_F(MorphTool, DamagedNormalMapsAreInvalidInput) {
  const fs::path bake = dir_ / "bake";
  write_bake(bake, "a", qs::io::read_mesh(R() / "a.obj").mesh);
  const std::string good = flat_normal_png(8, 8);
  std::string bad_crc = good;
  bad_crc[30] ^= 1;  // the IHDR chunk's checksum
  std::string tall = good;  // a header that promises 9 rows, its checksum right
  tall[23] = 9;
  const uint32_t c = crc32(tall.substr(12, 17));
  for (int k = 0; k < 4; ++k) tall[29 + k] = static_cast<char>(c >> (24 - 8 * k));
  const struct {
    std::string bytes, what;
  } damaged[] = {{good.substr(0, good.size() - 30), "the PNG ends early (truncated file"},
                 {bad_crc, "damaged PNG (a chunk's checksum does not match"},
                 {tall, "damaged PNG (its compressed pixel data does not decode to 8 x 9 pixels"},
                 {"not an image\n", "not a PNG file"},
                 {"", "empty file"}};
  const fs::path out = dir_ / "out";
  std::ofstream(bake / "c_normal.png", std::ios::binary) << good;
  for (const auto& d : damaged) {
    std::ofstream(bake / "b_normal.png", std::ios::binary) << d.bytes;
    const RunResult r = morph("--path a,b --frames 3 --bake " + bake.string() + " --frame-maps -q -o " + out.string());
    EXPECT_EQ(r.exit, 2) << r.out;
    EXPECT_THAT(r.out, HasSubstr("invalid input error: " + (bake / "b_normal.png").string() + ": " + d.what));
    EXPECT_THAT(r.out, HasSubstr("expected the 8-bit RGB normal map of shape 'b' written by qs-bake"));
    EXPECT_EQ(qs::test::quoted_library_phrase(r.out), "") << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST_F(MorphTool, FrameMapsGiveEveryFrameUvsAndItsOwnNormalMap) {
  const fs::path bake = dir_ / "bake";
  write_bake(bake, "a", qs::io::read_mesh(R() / "a.obj").mesh);
  std::ofstream(bake / "b_normal.png", std::ios::binary) << flat_normal_png(8, 8);
  const fs::path out = dir_ / "out";
  const std::string args = "--path a,b --frames 3 --bake " + bake.string() + " --frame-maps -q -o " + out.string();
  // Every normal map is read before anything is written.
  RunResult r = morph(args);
  EXPECT_EQ(r.exit, 3) << r.out;
  EXPECT_THAT(r.out, HasSubstr("c_normal.png: no such file"));
  EXPECT_FALSE(fs::exists(out));
  std::ofstream(bake / "c_normal.png", std::ios::binary) << flat_normal_png(8, 8);
  r = morph(args);
  ASSERT_EQ(r.exit, 0) << r.out;
  for (int f = 0; f < 3; ++f) {
    const std::string stem = "frame_000" + std::to_string(f);
    EXPECT_TRUE(fs::exists(out / (stem + "_normal.png"))) << stem;
    EXPECT_THAT(read_bytes(out / (stem + ".mtl")), HasSubstr("norm " + stem + "_normal.png"));
    EXPECT_THAT(read_bytes(out / (stem + ".obj")), HasSubstr("mtllib " + stem + ".mtl"));
  }
  EXPECT_EQ(qs::io::read_mesh(out / "frame_0000.obj").mesh.positions, shape("a"));
  EXPECT_EQ(qs::io::read_mesh(out / "frame_0002.obj").mesh.positions, shape("b"));
  EXPECT_EQ(read_bytes(out / "frame_0000_normal.png"), read_bytes(bake / "a_normal.png"));
  std::ifstream in(out / "morph.json");
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["frames"]["list"][1]["normal_map"], "frame_0001_normal.png");
  EXPECT_EQ(j["options"]["frame_maps"], true);

  const RunResult no_bake = morph("--frame-maps -o " + out.string());
  EXPECT_EQ(no_bake.exit, 1) << no_bake.out;
  EXPECT_THAT(no_bake.out, HasSubstr("--frame-maps needs --bake"));
  const RunResult ply = morph("--frame-maps --bake " + bake.string() + " --format ply -o " + out.string());
  EXPECT_EQ(ply.exit, 1) << ply.out;
  EXPECT_THAT(ply.out, HasSubstr("OBJ + MTL"));
}
