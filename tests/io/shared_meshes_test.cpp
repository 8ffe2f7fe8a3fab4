// Reads every mesh of the shared test-mesh folder and checks its counts against the folder's
// README table. Skipped when the folder is absent. The folder: $QS_SHARED_MESHES, or
// <repo>/../shared/meshes.

#include "../common/shared_meshes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include "qs/io/read_mesh.h"

namespace {

namespace fs = std::filesystem;

using qs::testing::shared_meshes_dir;

/// file -> (V, F) from the README's table rows "| file | what | V | F | ...". Files of a table
/// with a "genus" column (the higher-genus meshes, given as the sources wrote them) go to
/// `polygonal_ok`: their faces may be polygons, and F counts the file's polygons.
std::map<std::string, std::pair<int, int>> readme_counts(const fs::path& readme,
                                                         std::map<std::string, bool>* polygonal_ok = nullptr) {
  std::map<std::string, std::pair<int, int>> counts;
  bool genus_table = false;
  std::ifstream in(readme);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, '|')) {
      const auto b = cell.find_first_not_of(' ');
      const auto e = cell.find_last_not_of(' ');
      cells.push_back(b == std::string::npos ? "" : cell.substr(b, e - b + 1));
    }
    if (cells.size() < 5) {
      genus_table = false;
      continue;
    }
    if (std::find(cells.begin(), cells.end(), "genus") != cells.end()) genus_table = true;
    const std::string& file = cells[1];
    const fs::path p(file);
    if (p.extension() != ".obj" && p.extension() != ".off" && p.extension() != ".ply" && p.extension() != ".stl")
      continue;
    try {
      counts[file] = {std::stoi(cells[3]), std::stoi(cells[4])};
      if (polygonal_ok) (*polygonal_ok)[file] = genus_table;
    } catch (const std::exception&) {
    }
  }
  return counts;
}

TEST(SharedMeshes, CountsMatchTheReadme) {
  const fs::path dir = shared_meshes_dir();
  if (!fs::is_directory(dir) || !fs::exists(dir / "README.md"))
    GTEST_SKIP() << "no shared mesh folder at " << dir;
  std::map<std::string, bool> polygonal_ok;
  const auto table = readme_counts(dir / "README.md", &polygonal_ok);
  const std::map<std::string, std::pair<int, int>> must = {{"knight_1k.off", {502, 1000}},
                                                           {"venus_100k.off", {50002, 100000}},
                                                           {"camel_4k_fixed.obj", {1790, 3576}},
                                                           {"horse_40k.off", {19851, 39698}},
                                                           {"spot_2k.obj", {829, 1654}}};
  for (const auto& [file, vf] : must) {
    ASSERT_TRUE(table.count(file)) << file << " missing from the README table";
    EXPECT_EQ(table.at(file), vf) << file;
  }
  int read = 0;
  for (const auto& [file, vf] : table) {
    const fs::path path = dir / file;
    if (!fs::exists(path)) {
      EXPECT_FALSE(must.count(file)) << file << " is missing";
      continue;
    }
    const auto r = qs::io::read_mesh(path);
    EXPECT_EQ(r.mesh.num_vertices(), vf.first) << file;
    if (polygonal_ok[file]) {
      // A polygon of n corners is read as n - 2 triangles.
      EXPECT_GE(r.mesh.num_faces(), vf.second) << file;
    } else {
      EXPECT_EQ(r.mesh.num_faces(), vf.second) << file;
      EXPECT_EQ(r.report.polygons_triangulated, 0) << file;
    }
    EXPECT_EQ(r.report.degenerate_polygons_dropped, 0) << file;
    ++read;
  }
  EXPECT_GE(read, 5);
}

}  // namespace
