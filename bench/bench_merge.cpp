// Benchmark: the exact merge of two charts (qs-merge) on dissections of pairs.
//   usage: qs-bench-merge DISSECTION_DIR...   (bench/merge_pairs.sh dissects the four pairs)
// Prints, per pair: chart faces, merged faces and their ratio to the inputs, crossings, slivers,
// the median wall and CPU time of the merge on 1 and 2 threads (5 runs each), CPU microseconds per
// merged face (near-constant = near-linear time), and whether 1 and 2 threads gave identical
// output; then the exactness checks: every chart vertex of A (B) bitwise in the merged mesh at
// t = 0 (t = 1), the relative difference of the total areas, the merge of each chart with itself
// equal to the chart face for face, and the time of that self-merge. Wall time on a shared machine is only as good as its load: the CPU time is the figure
// to compare (target: pig_4k + cow2_9k under 0.5 s).

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "qs/core/error.h"
#include "qs/dissect/dissection_json.h"
#include "qs/merge/merge.h"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double cpu_seconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double area(const std::vector<qs::Vec3>& P, const std::vector<qs::Tri>& faces) {
  double s = 0;
  for (const auto& t : faces) s += 0.5 * (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]).norm();
  return s;
}

// Chart vertices found bitwise at their merged vertex.
bool bitwise(const qs::dissect::Chart& c, const std::vector<int>& vmap, const std::vector<qs::Vec3>& P) {
  std::vector<int> seen(c.mesh.num_vertices(), 0);
  for (size_t v = 0; v < vmap.size(); ++v)
    if (vmap[v] >= 0) {
      if (P[v] != c.mesh.positions[vmap[v]]) return false;
      ++seen[vmap[v]];
    }
  return std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; });
}

// The self-merge gives the chart's faces back (as chart vertex triples, each rotated to start at
// its lowest id; the merge lists them patch by patch).
bool self_merge_is_chart(const qs::dissect::Chart& c, const qs::merge::Merged& m) {
  if (m.faces.size() != c.mesh.faces.size()) return false;
  std::vector<std::array<int, 3>> x, y;
  for (const auto& t : m.faces) {
    std::array<int, 3> r{m.vertex_a[t[0]], m.vertex_a[t[1]], m.vertex_a[t[2]]};
    std::rotate(r.begin(), std::min_element(r.begin(), r.end()), r.end());
    x.push_back(r);
  }
  for (const auto& t : c.mesh.faces) {
    std::array<int, 3> r{t[0], t[1], t[2]};
    std::rotate(r.begin(), std::min_element(r.begin(), r.end()), r.end());
    y.push_back(r);
  }
  std::sort(x.begin(), x.end());
  std::sort(y.begin(), y.end());
  return x == y;
}

// The largest distance of a merged vertex from the plane of a parent face of a face using it,
// at t = 0 (A) or t = 1 (B), relative to the chart's bounding-box diagonal.
double off_parent_plane(const qs::dissect::Chart& c, const std::vector<int>& parent, const std::vector<qs::Vec3>& P,
                        const std::vector<qs::Tri>& faces) {
  double worst = 0;
  for (size_t f = 0; f < faces.size(); ++f) {
    const auto& t = c.mesh.faces[parent[f]];
    const auto& Q = c.mesh.positions;
    const qs::Vec3 n = (Q[t[1]] - Q[t[0]]).cross(Q[t[2]] - Q[t[0]]);
    if (n.norm() == 0) continue;
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::abs((P[faces[f][k]] - Q[t[0]]).dot(n)) / n.norm());
  }
  return worst / qs::bounding_box(c.mesh.positions).diagonal();
}

// Faces whose rounded uv (as written to remesh.json) are not counter-clockwise, counted on the
// faces whose three vertices record the face's own patch (the exact points always are).
int flat_in_rounded_uv(const qs::merge::Merged& m) {
  int n = 0;
  for (size_t f = 0; f < m.faces.size(); ++f) {
    const auto& t = m.faces[f];
    if (m.vertex_patch[t[0]] != m.face_patch[f] || m.vertex_patch[t[1]] != m.face_patch[f] ||
        m.vertex_patch[t[2]] != m.face_patch[f])
      continue;
    const qs::Vec2 &p = m.vertex_uv[t[0]], &q = m.vertex_uv[t[1]], &r = m.vertex_uv[t[2]];
    n += !((q - p).x() * (r - p).y() - (q - p).y() * (r - p).x() > 0);
  }
  return n;
}

bool same(const qs::merge::Merged& a, const qs::merge::Merged& b) {
  return a.faces == b.faces && a.positions_a == b.positions_a && a.positions_b == b.positions_b &&
         a.vertex_uv == b.vertex_uv && a.vertex_patch == b.vertex_patch;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: qs-bench-merge DISSECTION_DIR...  (dissections of two meshes)\n");
    return 1;
  }
  std::printf("%-34s %7s %7s %8s %5s %8s %8s %9s %9s %9s %9s %7s %5s\n", "pair", "faces A", "faces B", "merged",
              "ratio", "crossing", "slivers", "wall 1t", "cpu 1t", "wall 2t", "cpu 2t", "us/face", "same");
  for (int i = 1; i < argc; ++i) {
    try {
      const auto in = qs::dissect::read_dissection(argv[i]);
      if (in.meshes.size() != 2) {
        std::fprintf(stderr, "%s: %zu meshes, skipped\n", argv[i], in.meshes.size());
        continue;
      }
      const auto& a = in.meshes[0].dissection.chart;
      const auto& b = in.meshes[1].dissection.chart;
      qs::merge::Merged first[2];
      double wall[2], cpu[2];
      for (int t = 0; t < 2; ++t) {
        qs::merge::MergeOptions o;
        o.threads = t + 1;
        std::vector<double> w, c;
        for (int r = 0; r < 5; ++r) {
          const double c0 = cpu_seconds();
          const auto t0 = Clock::now();
          qs::merge::Merged m = qs::merge::merge_charts(a, b, o);
          w.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
          c.push_back(cpu_seconds() - c0);
          if (r == 0) first[t] = std::move(m);
        }
        wall[t] = median(w);
        cpu[t] = median(c);
      }
      const auto& m = first[0];
      const auto& st = m.stats;
      const std::string name = fs::path(in.meshes[0].file).stem().string() + " + " + fs::path(in.meshes[1].file).stem().string();
      std::printf("%-34s %7d %7d %8zu %5.2f %8d %8d %8.3fs %8.3fs %8.3fs %8.3fs %7.2f %5s\n", name.c_str(),
                  st.input_faces_a, st.input_faces_b, m.faces.size(),
                  static_cast<double>(m.faces.size()) / (st.input_faces_a + st.input_faces_b), st.crossings, st.slivers_uv,
                  wall[0], cpu[0], wall[1], cpu[1], 1e6 * cpu[0] / m.faces.size(), same(first[0], first[1]) ? "yes" : "NO");
      const double area_a = area(a.mesh.positions, a.mesh.faces), area_b = area(b.mesh.positions, b.mesh.faces);
      const double c0 = cpu_seconds();
      const qs::merge::Merged self = qs::merge::merge_charts(a, a);
      const double self_cpu = cpu_seconds() - c0;
      std::printf("  exact: A bitwise %s, B bitwise %s, off parent planes A %.1e B %.1e, area rel. diff A %.2e B %.2e; min angle uv %.2e deg; thin "
                  "faces %d/%d, normals off %d/%d, not CCW in rounded uv %d, side points moved %d; self-merge of A %s the chart (%.3f s cpu)\n",
                  bitwise(a, m.vertex_a, m.positions_a) ? "yes" : "NO", bitwise(b, m.vertex_b, m.positions_b) ? "yes" : "NO",
                  off_parent_plane(a, m.face_parent_a, m.positions_a, m.faces),
                  off_parent_plane(b, m.face_parent_b, m.positions_b, m.faces),
                  std::abs(area(m.positions_a, m.faces) - area_a) / area_a,
                  std::abs(area(m.positions_b, m.faces) - area_b) / area_b, st.min_angle_uv, st.thin_faces_a,
                  st.thin_faces_b, st.normal_disagreements_a, st.normal_disagreements_b, flat_in_rounded_uv(m), st.side_points_moved,
                  self_merge_is_chart(a, self) ? "is" : "is NOT", self_cpu);
    } catch (const qs::Error& e) {
      std::fprintf(stderr, "%s: %s\n", argv[i], e.what());
      return 2;
    }
  }
  return 0;
}
