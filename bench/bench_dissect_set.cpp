// Benchmark: dissecting sets of meshes together (union quinary tree + feature alignment), as
// qs-dissect does (qs::pipeline::dissect_meshes: the map hooks, same-pose detection, refine_maps).
//   usage: qs-bench-dissect-set [MESH_DIR]   (default ../shared/meshes)
// Prints, per set: meshes, common patches, max stretch, features, warp flips, time, and the
// time per 10k input faces; then the scaling of one mesh repeated 1, 2, 4, 8 times.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissection.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/pipeline/pipeline.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

struct Loaded {
  std::string name;
  qs::TriMesh mesh;
};

Loaded load(const fs::path& p) {
  const auto r = qs::io::read_mesh(p);
  auto v = qs::mesh::validate(r.mesh);
  return {p.stem().string(), std::move(v.mesh)};
}

// cat_lion_markers.yml: lines `- "CAT:LION"  #comment`, vertex ids in file order. The validated
// meshes keep vertex ids (these files have no unreferenced vertices).
std::vector<std::pair<std::array<int, 2>, std::string>> read_markers(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::pair<std::array<int, 2>, std::string>> out;
  const std::regex re(R"re(-\s*"(\d+):(\d+)"\s*#\s*(.*\S))re");
  std::smatch m;
  for (std::string line; std::getline(in, line);)
    if (std::regex_search(line, m, re)) out.push_back({{std::stoi(m[1]), std::stoi(m[2])}, m[3]});
  return out;
}

void run(const std::string& label, const std::vector<qs::dissect::MeshToDissect>& set) {
  long faces = 0;
  for (const auto& m : set) faces += static_cast<long>(m.mesh->faces.size());
  const auto t0 = Clock::now();
  try {
    const auto s = qs::pipeline::dissect_meshes(set).set;
    const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
    int over = 0, nonbij = 0;
    for (const auto& d : s.meshes)
      for (const auto& p : d.chart.patches) {
        over += p.stop != qs::dissect::StopReason::None;
        nonbij += p.flipped_faces + p.zero_area_faces;
      }
    double feature_spread = 0;  // max uv distance of a feature from its counterpart in mesh 0
    for (const auto& d : s.meshes)
      for (size_t k = 0; k < d.features.size(); ++k) {
        const auto& f0 = s.meshes[0].features[k];
        feature_spread = std::max(feature_spread, d.features[k].patch != f0.patch ? 1.0 : (d.features[k].uv - f0.uv).norm());
      }
    std::printf("%-44s %6zu %8ld %8zu %10.3g %4d/%-4d %9zu %8d %9.2g %8.3f %10.3f\n", label.c_str(), set.size(), faces,
                s.meshes[0].chart.patches.size(), s.max_stretch, over, nonbij, s.meshes[0].features.size(),
                s.warp_events, feature_spread, sec, sec / (faces / 1e4));
  } catch (const qs::Error& e) {
    std::printf("%-44s FAILED: %s\n", label.c_str(), e.what());
  }
}

}  // namespace

int main(int argc, char** argv) {
  const fs::path dir = argc > 1 ? argv[1] : QS_SOURCE_DIR "/../shared/meshes";
  if (!fs::is_directory(dir)) {
    std::fprintf(stderr, "qs-bench-dissect-set: %s is not a folder of meshes\n", dir.string().c_str());
    return 2;
  }
  std::printf("%-44s %6s %8s %8s %10s %8s %9s %8s %9s %8s %10s\n", "set", "meshes", "faces", "patches", "max L2",
              "stop/fold", "features", "flips", "f.spread", "time s", "s/10k f");
  std::map<std::string, Loaded> m;
  for (const char* f : {"horse_5k.obj", "camel_4k_fixed.obj", "cat_sumner_14k.obj", "lion_sumner_10k.obj",
                        "max_planck_11k.obj", "igea_17k.off", "mannequin_head_23k.off", "venus_100k.off",
                        "spot_6k.obj", "pig_4k.off"})
    m[f] = load(dir / f);
  auto mk = [&](const char* f) {
    qs::dissect::MeshToDissect t;
    t.mesh = &m.at(f).mesh;
    t.name = f;
    return t;
  };
  run("horse_5k + camel_4k_fixed (automatic seeds)", {mk("horse_5k.obj"), mk("camel_4k_fixed.obj")});

  // Cat and lion: 4 markers on a belt around the torso as seeds, the others as features.
  const auto markers = read_markers(dir / "cat_lion_markers.yml");
  const std::vector<std::string> seed_names = {"mid back", "left hind quarters", "belly", "right hind quarters"};
  auto cat = mk("cat_sumner_14k.obj"), lion = mk("lion_sumner_10k.obj");
  cat.seeds = lion.seeds = std::array<int, 4>{};
  int found = 0;
  for (const auto& [ids, name] : markers) {
    const auto it = std::find(seed_names.begin(), seed_names.end(), name);
    if (it != seed_names.end()) {
      (*cat.seeds)[it - seed_names.begin()] = ids[0];
      (*lion.seeds)[it - seed_names.begin()] = ids[1];
      ++found;
    } else {
      cat.features.push_back({name, ids[0], {}});
      lion.features.push_back({name, ids[1], {}});
    }
  }
  if (found == 4) {
    run("cat_sumner_14k + lion_sumner_10k (seeds only)", {[&] { auto c = cat; c.features.clear(); return c; }(),
                                                          [&] { auto l = lion; l.features.clear(); return l; }()});
    // The documented subset: features that both seed loops leave on the same side (the others
    // are reported by dissect_set one at a time and dropped here).
    std::vector<std::string> dropped;
    for (int round = 0; round < 60; ++round) {
      try {
        qs::dissect::DissectOptions probe;
        probe.max_depth = 0;
        qs::dissect::dissect_set({cat, lion}, probe);
        break;
      } catch (const qs::InvalidInput& e) {
        const std::string msg = e.what();
        const size_t a = msg.find("feature '"), b = msg.find("' lies in seed patch");
        if (a == std::string::npos || b == std::string::npos) break;
        const std::string name = msg.substr(a + 9, b - a - 9);
        dropped.push_back(name);
        auto drop = [&](std::vector<qs::dissect::Feature>& v) {
          v.erase(std::remove_if(v.begin(), v.end(), [&](const auto& f) { return f.name == name; }), v.end());
        };
        drop(cat.features);
        drop(lion.features);
      }
    }
    std::printf("  (cat/lion: %zu features dropped as the seed loops separate them:", dropped.size());
    for (const auto& d : dropped) std::printf(" '%s'", d.c_str());
    std::printf(")\n");
    run("cat_sumner_14k + lion_sumner_10k (" + std::to_string(cat.features.size()) + " features)", {cat, lion});
  } else {
    std::printf("cat/lion: cat_lion_markers.yml lacks the seed markers\n");
  }
  run("four heads (automatic seeds)",
      {mk("max_planck_11k.obj"), mk("igea_17k.off"), mk("mannequin_head_23k.off"), mk("venus_100k.off")});
  run("spot_6k + pig_4k (automatic seeds)", {mk("spot_6k.obj"), mk("pig_4k.off")});
  for (int n : {1, 2, 4, 8}) {
    std::vector<qs::dissect::MeshToDissect> set(n, mk("horse_5k.obj"));
    run("horse_5k x " + std::to_string(n), set);
  }
  return 0;
}
