// The corrupted-input set: every reader must throw InvalidInput (or IoError for a file that
// cannot be read) with a useful message, and never crash, hang or over-allocate.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <unistd.h>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <random>

#include "qs/core/error.h"
#include "qs/io/read_mesh.h"
#include "qs/io/write_mesh.h"

namespace {

namespace fs = std::filesystem;
using qs::io::MeshFormat;
using qs::io::read_mesh_from_memory;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

const MeshFormat kAll[] = {MeshFormat::Obj, MeshFormat::Off, MeshFormat::Ply, MeshFormat::Stl};

qs::TriMesh octahedron() {
  qs::TriMesh m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.faces = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

std::string binary_ply_octahedron(bool big) {
  const qs::TriMesh m = octahedron();
  std::string out = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 8\nproperty list uchar int vertex_indices\nend_header\n";
  auto put = [&](auto v) {
    char b[sizeof v];
    std::memcpy(b, &v, sizeof v);
    if (big) std::reverse(b, b + sizeof v);
    out.append(b, sizeof v);
  };
  for (const auto& p : m.positions)
    for (int k = 0; k < 3; ++k) put(static_cast<float>(p[k]));
  for (const auto& f : m.faces) {
    put(std::uint8_t{3});
    for (int id : f) put(static_cast<std::int32_t>(id));
  }
  return out;
}

std::string binary_stl_octahedron() {
  const qs::TriMesh m = octahedron();
  std::string out(80, 'x');
  const std::uint32_t n = 8;
  out.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& f : m.faces) {
    out.append(12, '\0');
    for (int id : f)
      for (int k = 0; k < 3; ++k) {
        const float v = static_cast<float>(m.positions[static_cast<std::size_t>(id)][k]);
        out.append(reinterpret_cast<const char*>(&v), 4);
      }
    out.append(2, '\0');
  }
  return out;
}

std::string ascii_stl_octahedron() {
  const qs::TriMesh m = octahedron();
  std::string out = "solid octa\n";
  for (const auto& f : m.faces) {
    out += "facet normal 0 0 0\nouter loop\n";
    for (int id : f) {
      const auto& p = m.positions[static_cast<std::size_t>(id)];
      out += "vertex " + std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
    }
    out += "endloop\nendfacet\n";
  }
  return out + "endsolid octa\n";
}

struct Sample {
  const char* label;
  MeshFormat format;
  std::string data;
};

std::vector<Sample> samples() {
  const qs::TriMesh m = octahedron();
  return {{"obj", MeshFormat::Obj, qs::io::mesh_to_string(m, MeshFormat::Obj)},
          {"off", MeshFormat::Off, qs::io::mesh_to_string(m, MeshFormat::Off)},
          {"ply_ascii", MeshFormat::Ply, qs::io::mesh_to_string(m, MeshFormat::Ply)},
          {"ply_le", MeshFormat::Ply, binary_ply_octahedron(false)},
          {"ply_be", MeshFormat::Ply, binary_ply_octahedron(true)},
          {"stl_ascii", MeshFormat::Stl, ascii_stl_octahedron()},
          {"stl_binary", MeshFormat::Stl, binary_stl_octahedron()}};
}

TEST(Corrupt, SamplesReadCleanly) {
  for (const Sample& s : samples()) {
    const auto r = read_mesh_from_memory(s.data, s.format, s.label);
    EXPECT_EQ(r.mesh.num_faces(), 8) << s.label;
  }
}

/// Every proper prefix of every sample either throws InvalidInput or (for OBJ, which has no
/// counts, cut at a line end) reads a smaller mesh; nothing else.
TEST(Corrupt, EveryTruncationIsHandled) {
  for (const Sample& s : samples()) {
    int rejected = 0;
    for (std::size_t len = 0; len < s.data.size(); ++len) {
      try {
        const auto r = read_mesh_from_memory(std::string_view(s.data).substr(0, len), s.format, s.label);
        EXPECT_LE(r.mesh.num_faces(), 8) << s.label << " cut at " << len;
        for (const auto& f : r.mesh.faces)
          for (int id : f) ASSERT_TRUE(id >= 0 && id < r.mesh.num_vertices()) << s.label << " cut at " << len;
      } catch (const qs::InvalidInput&) {
        ++rejected;
      }
    }
    if (s.format != MeshFormat::Obj) {
      // Formats with counts or end markers notice nearly every cut (an OFF or PLY cut inside
      // the last number still parses).
      // An ASCII STL's "endsolid" may omit the solid's name, so cuts inside the name pass.
      const int slack = s.label == std::string("stl_ascii") ? 15 : 3;
      EXPECT_GE(rejected, static_cast<int>(s.data.size()) - slack) << s.label;
    }
  }
}

/// Random byte changes in valid files: the reader either reads a mesh whose faces are all in
/// range or throws InvalidInput; nothing else.
TEST(Corrupt, RandomByteChanges) {
  std::mt19937 rng(11);
  for (const Sample& s : samples()) {
    for (int trial = 0; trial < 300; ++trial) {
      std::string data = s.data;
      const int changes = 1 + static_cast<int>(rng() % 4);
      for (int c = 0; c < changes; ++c) {
        const char pool[] = "0123456789 -+.e\n#/\xff" "\x00" "abc";
        data[rng() % data.size()] = rng() % 2 ? static_cast<char>(rng()) : pool[rng() % (sizeof pool - 1)];
      }
      try {
        const auto r = read_mesh_from_memory(data, s.format, s.label);
        for (const auto& f : r.mesh.faces)
          for (int id : f) ASSERT_TRUE(id >= 0 && id < r.mesh.num_vertices()) << s.label;
      } catch (const qs::InvalidInput& e) {
        EXPECT_THAT(e.what(), HasSubstr(s.label));
      }
    }
  }
}

TEST(Corrupt, TruncatedMessagesSayWhere) {
  const auto all = samples();
  const std::string& off = all[1].data;
  EXPECT_THAT([&] { read_mesh_from_memory(off.substr(0, off.size() / 2), MeshFormat::Off, "cut.off"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("cut.off:")));
  const std::string& ply = all[3].data;
  EXPECT_THAT([&] { read_mesh_from_memory(ply.substr(0, ply.size() - 5), MeshFormat::Ply, "cut.ply"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("cut.ply: byte offset")));
  EXPECT_THAT([&] { read_mesh_from_memory(ply.substr(0, ply.size() - 5), MeshFormat::Ply, "cut.ply"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("file ends inside face 7 of 8")));
}

TEST(Corrupt, BinaryGarbageInEveryFormat) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    std::string garbage(1 + rng() % 4000, '\0');
    for (char& c : garbage) c = static_cast<char>(rng());
    for (MeshFormat f : kAll) {
      try {
        read_mesh_from_memory(garbage, f, "garbage");
      } catch (const qs::InvalidInput& e) {
        EXPECT_THAT(e.what(), HasSubstr("garbage"));
      }
    }
    // Garbage after a valid-looking header.
    for (const char* header : {"OFF\n3 1 0\n", "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
                               "property float x\nproperty float y\nproperty float z\nelement face 1\n"
                               "property list uchar int vertex_indices\nend_header\n"}) {
      const MeshFormat f = header[0] == 'O' ? MeshFormat::Off : MeshFormat::Ply;
      try {
        read_mesh_from_memory(std::string(header) + garbage, f, "garbage");
      } catch (const qs::InvalidInput&) {
      }
    }
  }
  EXPECT_THAT([] { read_mesh_from_memory(std::string("v 1 2 3\n\x01\x00\xff", 11), MeshFormat::Obj, "g.obj"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("g.obj:2: unexpected binary data")));
}

TEST(Corrupt, HugeCountsAreRefusedBeforeAllocating) {
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THAT([] { read_mesh_from_memory("OFF\n1000000000000 1 0\n0 0 0\n", MeshFormat::Off, "huge.off"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("huge.off:2: header claims 1000000000000 vertices")));
  EXPECT_THAT([] { read_mesh_from_memory("OFF\n1000000 1 0\n0 0 0\n", MeshFormat::Off, "huge.off"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("header claims 1000000 vertices but the file has only")));
  EXPECT_THAT([] { read_mesh_from_memory("OFF\n1 100000000 0\n0 0 0\n", MeshFormat::Off, "huge.off"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("header claims 100000000 faces")));
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    const std::string ply = std::string("ply\nformat ") + format +
                            " 1.0\nelement vertex 1000000000000\nproperty float x\nproperty float y\n"
                            "property float z\nend_header\n0 0 0\n";
    EXPECT_THAT([&] { read_mesh_from_memory(ply, MeshFormat::Ply, "huge.ply"); },
                ThrowsMessage<qs::InvalidInput>(HasSubstr("huge.ply:3: header claims 1000000000000 vertices")));
    const std::string ply2 = std::string("ply\nformat ") + format +
                             " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                             "element face 50000000\nproperty list uchar int vertex_indices\nend_header\n"
                             "000000000000000000000000000000000000\n";
    EXPECT_THAT([&] { read_mesh_from_memory(ply2, MeshFormat::Ply, "huge.ply"); },
                ThrowsMessage<qs::InvalidInput>(HasSubstr("huge.ply:7: header claims 50000000 faces")));
    // An element with no properties and a huge count must not loop.
    const std::string ply3 = std::string("ply\nformat ") + format +
                             " 1.0\nelement nothing 1000000000000000\nelement vertex 0\nproperty float x\n"
                             "property float y\nproperty float z\nend_header\n";
    EXPECT_NO_THROW(read_mesh_from_memory(ply3, MeshFormat::Ply, "huge.ply"));
  }
  // A binary list that claims 4 billion entries.
  std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
  ply += std::string(36, '\0') + "\xff\xff\xff\xff";
  EXPECT_THAT([&] { read_mesh_from_memory(ply, MeshFormat::Ply, "huge.ply"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("file ends inside face 0 of 1")));
  // Binary STL claiming 4 billion triangles.
  std::string stl(80, ' ');
  stl += "\xff\xff\xff\xff";
  stl += std::string(100, '\0');
  EXPECT_THAT([&] { read_mesh_from_memory(stl, MeshFormat::Stl, "huge.stl"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("header claims 4294967295 triangles")));
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
}

TEST(Corrupt, NanAndInfCoordinatesAreReadAsIs) {
  const auto off = read_mesh_from_memory("OFF\n3 1 0\nnan 0 0\n1 inf 0\n0 1 -inf\n3 0 1 2\n", MeshFormat::Off, "n.off");
  EXPECT_TRUE(std::isnan(off.mesh.positions[0].x()));
  EXPECT_TRUE(std::isinf(off.mesh.positions[1].y()));
  EXPECT_LT(off.mesh.positions[2].z(), 0);
  const auto obj = read_mesh_from_memory("v NaN 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", MeshFormat::Obj, "n.obj");
  EXPECT_TRUE(std::isnan(obj.mesh.positions[0].x()));
  // Out-of-range literals are read as a parser would (infinity), not rejected.
  const auto big = read_mesh_from_memory("v 1e999 -1e999 1e-999\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", MeshFormat::Obj, "b.obj");
  EXPECT_TRUE(std::isinf(big.mesh.positions[0].x()));
  EXPECT_LT(big.mesh.positions[0].y(), 0);
  EXPECT_EQ(big.mesh.positions[0].z(), 0.0);
  // Binary NaN.
  std::string stl(80, ' ');
  const std::uint32_t n = 1;
  stl.append(reinterpret_cast<const char*>(&n), 4);
  const float v[12] = {0, 0, 0, std::nanf(""), 0, 0, 1, 0, 0, 0, 1, 0};
  stl.append(reinterpret_cast<const char*>(v), sizeof v);
  stl.append(2, '\0');
  EXPECT_TRUE(std::isnan(read_mesh_from_memory(stl, MeshFormat::Stl, "n.stl").mesh.positions[0].x()));
}

TEST(Corrupt, UnparsableNumbersAreRejected) {
  EXPECT_THAT([] { read_mesh_from_memory("OFF\n3 1 0\n0 0 0\n1 0x1 0\n0 1 0\n3 0 1 2\n", MeshFormat::Off, "u.off"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("u.off:4: vertex coordinate '0x1' is not a number")));
  EXPECT_THAT([] { read_mesh_from_memory("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2.5\n", MeshFormat::Off, "u.off"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("u.off:6: vertex index '2.5' is not an integer")));
}

TEST(Corrupt, EmptyFiles) {
  for (MeshFormat f : kAll) {
    EXPECT_THAT([&] { read_mesh_from_memory("", f, "empty"); },
                ThrowsMessage<qs::InvalidInput>(HasSubstr("empty: file is empty")));
    EXPECT_THAT([&] { read_mesh_from_memory(" \n\r\n\t", f, "blank"); },
                ThrowsMessage<qs::InvalidInput>(HasSubstr("blank: file contains only white space")));
  }
}

class TempDir {
 public:
  TempDir() : path_(fs::temp_directory_path() / ("qs_io_corrupt_" + std::to_string(::getpid()))) {
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

TEST(Corrupt, FilesOnDisk) {
  TempDir dir;
  EXPECT_THAT([&] { qs::io::read_mesh(dir.path() / "missing.off"); },
              ThrowsMessage<qs::IoError>(HasSubstr("missing.off: cannot open for reading")));
  EXPECT_THAT([&] { qs::io::read_mesh(dir.path() / "mesh.3ds"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("supported extensions are .obj .off .ply .stl")));
  EXPECT_THAT([&] { qs::io::read_mesh(dir.path() / "mesh"); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr("no extension")));
  fs::create_directories(dir.path() / "dir.obj");
  EXPECT_THROW(qs::io::read_mesh(dir.path() / "dir.obj"), qs::IoError);
  const fs::path empty = dir.path() / "empty.OBJ";  // the extension is case-insensitive
  { std::ofstream(empty.string()).flush(); }
  EXPECT_THAT([&] { qs::io::read_mesh(empty); }, ThrowsMessage<qs::InvalidInput>(HasSubstr("file is empty")));
  // A good file, and an error message naming the path.
  const fs::path good = dir.path() / "good.off";
  qs::io::write_mesh(good, octahedron());
  EXPECT_EQ(qs::io::read_mesh(good).mesh.num_faces(), 8);
  const fs::path bad = dir.path() / "bad.off";
  { std::ofstream(bad.string()) << "OFF\n3 1 0\n0 0 0\n1 0\n0 1 0\n3 0 1 2\n"; }
  EXPECT_THAT([&] { qs::io::read_mesh(bad); },
              ThrowsMessage<qs::InvalidInput>(HasSubstr(bad.string() + ":4: expected 3 vertex coordinates, found 2")));
  EXPECT_EQ(qs::io::format_from_path("a/b/C.Ply"), MeshFormat::Ply);
  EXPECT_STREQ(qs::io::format_name(MeshFormat::Stl), "STL");
}

}  // namespace
