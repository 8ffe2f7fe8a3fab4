// Relaxation of the seed loop's curves (paper 3.3, figure 6). See relax.h for the construction.
//
// One step (curve i):
//   1. Cut the closed CutMesh open along the slit s[i+1] -> s[i+2] -> s[i+3] -> s[i] (the other
//      three curves) into a PatchMesh: every inner slit vertex gets a second copy used by the
//      faces right of the slit (the side of seed patch 1); the faces left of it keep the original
//      id. Border, counter-clockwise from corner 0: the slit forward on the left copies from
//      s[i+2] to s[i] (corner 1 = s[i+3]), back on the right copies to s[i+1] (corners 2 = s[i+3]',
//      3 = s[i+2]'), then forward on the left copies to s[i+2] again.
//   2. Split the edges border_degeneracies lists (in the CutMesh) and cut open again, then solve.
//   3. Walk the UV segment from s[i] to s[i+1] through the disk's (static) UV triangulation,
//      recording events: "pass through local vertex v" or "cross local edge a->b at t". Nothing
//      is changed while walking, so a failed walk leaves the mesh as it was.
//   4. Replay the events on a copy of the CutMesh (each crossed edge is still there: a straight
//      segment crosses an edge once, and a split only removes the edge it splits), giving the new
//      edge path; check it (simple, off the other curves, cuts the mesh in two) and commit.

#include "qs/dissect/relax.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_set>
#include <utility>

#include "qs/core/error.h"
#include "qs/core/geometry2d.h"
#include "qs/dissect/cut_mesh.h"
#include "qs/param/square_param.h"

namespace qs::dissect {

namespace {

std::uint64_t edge_key(int a, int b) {
  return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint64_t>(std::max(a, b));
}

double length_of(const std::vector<Vec3>& positions, const std::vector<int>& path) {
  double sum = 0;
  for (std::size_t k = 1; k < path.size(); ++k) sum += (positions[path[k]] - positions[path[k - 1]]).norm();
  return sum;
}

/// A failed step: the curve is kept.
struct StepFailure {
  std::string why;
};

/// The closed mesh cut open along the three curves other than curve i.
struct Disk {
  param::PatchMesh pm;
  std::vector<int> global;   // local -> CutMesh vertex
  std::vector<char> border;  // local: on the disk's border
  int src = -1, dst = -1;    // local ids of s[i] and s[i+1]
};

Disk cut_open(const CutMesh& cm, const SeedLoop& loop, int i) {
  // slit[0] = s[i+1], ..., slit[n] = s[i]
  std::vector<int> slit;
  std::array<int, 3> edges{};
  for (int j = 1; j <= 3; ++j) {
    const auto& p = loop.paths[(i + j) % 4];
    slit.insert(slit.end(), p.begin() + (slit.empty() ? 0 : 1), p.end());
    edges[j - 1] = static_cast<int>(p.size()) - 1;
  }
  const int n = static_cast<int>(slit.size()) - 1;
  const int nv = cm.num_vertices();
  Disk d;
  d.pm.positions = cm.positions();
  d.pm.faces = cm.faces();
  d.global.resize(nv + n - 1);
  std::iota(d.global.begin(), d.global.begin() + nv, 0);
  auto left = [&](int j) { return slit[j]; };
  auto right = [&](int j) { return j == 0 || j == n ? slit[j] : nv + j - 1; };
  for (int j = 1; j < n; ++j) {
    const int v = slit[j], r = right(j);
    d.global[r] = v;
    d.pm.positions.push_back(cm.position(v));
    // Faces right of the slit p -> v -> n: counter-clockwise around v from v->p up to v->n.
    int h = cm.find_halfedge(v, slit[j - 1]);
    if (h < 0 || cm.find_halfedge(v, slit[j + 1]) < 0)
      throw StepFailure{"the other curves are not an edge path"};
    for (int guard = 0; cm.head(h) != slit[j + 1]; ++guard) {
      if (guard > 1 << 20) throw StepFailure{"a vertex fan does not close"};
      Tri& t = d.pm.faces[CutMesh::face_of(h)];
      for (int& c : t)
        if (c == v) c = r;
      h = cm.rotate_ccw(h);
    }
  }
  const int e1 = edges[0], e2 = edges[1], e3 = edges[2];
  auto& b = d.pm.boundary;
  for (int j = e1; j <= n; ++j) b.push_back(left(j));
  for (int j = n - 1; j >= 0; --j) b.push_back(right(j));
  for (int j = 1; j < e1; ++j) b.push_back(left(j));
  d.pm.corner_index = {0, e2, e2 + 2 * e3, 2 * e2 + 2 * e3};
  d.border.assign(d.pm.positions.size(), 0);
  for (int v : b) d.border[v] = 1;
  d.src = slit[n];
  d.dst = slit[0];
  return d;
}

/// One event of the walk, in local ids: b < 0 passes through vertex a; otherwise the segment
/// crosses edge a->b at parameter t from a.
struct Event {
  int a = -1, b = -1;
  double t = 0;
};

/// Walks the straight UV segment from d.src to d.dst through the disk's UV triangulation.
/// `avoid` flags CutMesh vertices never to pass through (local ids below its size are the same).
std::vector<Event> walk(const Disk& d, const std::vector<Vec2>& uv, double snap, const std::vector<char>& avoid) {
  const auto& F = d.pm.faces;
  const int nf = static_cast<int>(F.size());
  const int nv = static_cast<int>(uv.size());
  // Opposite half-edges (-1 on the border) and vertex -> faces.
  std::vector<int> opp(3 * nf, -1);
  {
    std::vector<std::pair<std::uint64_t, int>> keys(3 * nf);
    for (int h = 0; h < 3 * nf; ++h) keys[h] = {edge_key(F[h / 3][h % 3], F[h / 3][(h % 3 + 1) % 3]), h};
    std::sort(keys.begin(), keys.end());
    for (int k = 0; k + 1 < 3 * nf; ++k)
      if (keys[k].first == keys[k + 1].first) {
        opp[keys[k].second] = keys[k + 1].second;
        opp[keys[k + 1].second] = keys[k].second;
        ++k;
      }
  }
  std::vector<int> start(nv + 1, 0), fan(3 * nf);
  for (const Tri& t : F)
    for (int v : t) ++start[v + 1];
  for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
  {
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int f = 0; f < nf; ++f)
      for (int v : F[f]) fan[fill[v]++] = f;
  }
  auto tail = [&](int h) { return F[h / 3][h % 3]; };
  auto head = [&](int h) { return F[h / 3][(h % 3 + 1) % 3]; };
  auto next = [](int h) { return h % 3 == 2 ? h - 2 : h + 1; };
  auto prev = [](int h) { return h % 3 == 0 ? h + 2 : h - 1; };

  const double keep_off = std::min(snap, 0.01);  // crossings stay this far from an edge's ends
  std::vector<Event> events;
  std::vector<char> visited(nv, 0);
  for (std::size_t v = 0; v < avoid.size(); ++v) visited[v] = avoid[v];  // never passed through
  std::unordered_set<std::uint64_t> crossed;
  visited[d.src] = 1;
  const Vec2 q = uv[d.dst];
  const std::size_t limit = 4 * static_cast<std::size_t>(nf) + 16;
  int cur = d.src;
  for (;;) {
    if (events.size() > limit) throw StepFailure{"the walk did not reach its end"};
    const Vec2 p = uv[cur];
    const Vec2 dir = q - p;
    const double dn = dir.norm();
    if (!(dn > 0)) throw StepFailure{"two vertices of the walk share one UV point"};
    // The face around cur whose corner wedge holds the direction.
    int best_h = -1;
    double best = -std::numeric_limits<double>::infinity();
    for (int k = start[cur]; k < start[cur + 1]; ++k) {
      const int f = fan[k];
      const int c = F[f][0] == cur ? 0 : F[f][1] == cur ? 1 : 2;
      const int x = F[f][(c + 1) % 3], y = F[f][(c + 2) % 3];
      const Vec2 ex = uv[x] - p, ey = uv[y] - p;
      const double score = std::min(cross2(ex, dir) / (ex.norm() * dn + 1e-300),
                                    cross2(dir, ey) / (ey.norm() * dn + 1e-300));
      if (score > best) {
        best = score;
        best_h = 3 * f + (c + 1) % 3;  // x -> y
      }
    }
    if (best_h < 0 || best < -1e-6) throw StepFailure{"the segment leaves the disk at a vertex (folded UV triangles)"};
    if (tail(best_h) == d.dst || head(best_h) == d.dst) return events;
    int h = best_h;
    double s_prev = 0;
    for (;;) {
      if (events.size() > limit) throw StepFailure{"the walk did not reach its end"};
      const int x = tail(h), y = head(h);
      const Vec2 ux = uv[x], e = uv[y] - ux;
      const double denom = cross2(e, dir);
      if (!(std::abs(denom) > 1e-300)) throw StepFailure{"the segment runs along an edge"};
      const double t = std::clamp(cross2(p - ux, dir) / denom, 0.0, 1.0);
      const double s = cross2(ux - p, e) / cross2(dir, e);
      if (!(s < 1)) throw StepFailure{"the segment misses its end vertex (folded UV triangles)"};
      if (s < s_prev - 1e-9) throw StepFailure{"the walk turned back (folded UV triangles)"};
      s_prev = s;
      int through = -1;
      if (t < snap && !d.border[x] && !visited[x]) through = x;
      else if (t > 1 - snap && !d.border[y] && !visited[y]) through = y;
      if (through >= 0) {
        events.push_back({through, -1, 0});
        visited[through] = 1;
        cur = through;
        break;
      }
      const int g = opp[h];
      if (g < 0) throw StepFailure{"the segment crosses another curve"};
      if (!crossed.insert(edge_key(x, y)).second) throw StepFailure{"the segment crosses an edge twice (folded UV triangles)"};
      events.push_back({x, y, std::clamp(t, keep_off, 1 - keep_off)});
      // Into the face across: g = y->x, next(g) = x->w, prev(g) = w->y.
      const int w = F[g / 3][(g % 3 + 2) % 3];
      if (w == d.dst) return events;
      const double ow = cross2(dir, uv[w] - p), ox = cross2(dir, ux - p);
      h = (ow > 0) == (ox > 0) ? prev(g) : next(g);
    }
  }
}

/// Quick checks of a new curve against the other three: simple, off them, an edge path.
void check_curve(const CutMesh& cm, const SeedLoop& loop, int i, const std::vector<int>& path) {
  std::unordered_set<int> others;
  for (int j = 1; j <= 3; ++j)
    for (int v : loop.paths[(i + j) % 4]) others.insert(v);
  std::unordered_set<int> seen;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const int v = path[k];
    if (!seen.insert(v).second) throw StepFailure{"the new curve visits a vertex twice"};
    if (k > 0 && k + 1 < path.size() && others.count(v)) throw StepFailure{"the new curve touches another curve"};
    if (k > 0 && cm.find_halfedge(path[k - 1], v) < 0) throw StepFailure{"the new curve is not an edge path"};
  }
}

}  // namespace

double curve_length(const TriMesh& mesh, const std::vector<int>& path) {
  for (int v : path)
    if (v < 0 || v >= mesh.num_vertices())
      throw InvalidInput("curve_length: vertex " + std::to_string(v) + " outside [0, " +
                         std::to_string(mesh.num_vertices()) + ")");
  return length_of(mesh.positions, path);
}

RelaxedLoop relax_seed_loop(const TriMesh& mesh, const SeedLoop& loop, const RelaxOptions& options,
                            const Context& context) {
  if (options.rounds < 0 || options.rounds > 16)
    throw InvalidInput("relax_seed_loop: rounds is " + std::to_string(options.rounds) + "; expected 0 to 16");
  if (!(options.snap >= 0 && options.snap < 0.5))
    throw InvalidInput("relax_seed_loop: snap is " + std::to_string(options.snap) + "; expected 0 <= snap < 0.5");
  std::vector<char> avoid(mesh.num_vertices(), 0);
  for (int v : options.avoid) {
    if (v < 0 || v >= mesh.num_vertices())
      throw InvalidInput("relax_seed_loop: vertex " + std::to_string(v) + " to avoid is outside [0, " +
                         std::to_string(mesh.num_vertices()) + ")");
    avoid[v] = 1;
  }
  seed_patch_of_faces(mesh, loop);  // \throws InvalidInput: not a seed loop of this mesh
  CutMesh cm(mesh);                 // \throws InvalidInput: not closed and manifold

  // The side of every vertex to avoid, kept by every step (-1: on the input loop, not checked).
  const std::vector<int> sides =
      options.keep_sides && !options.avoid.empty() ? sides_of_vertices(mesh, loop, options.avoid) : std::vector<int>{};
  RelaxedLoop out;
  out.loop = loop;
  for (int i = 0; i < 4; ++i) out.length_before[i] = length_of(mesh.positions, loop.paths[i]);
  const Context quiet = context.without_progress();
  const int total = 4 * options.rounds;
  for (int step = 0; step < total; ++step) {
    context.check_cancel();
    context.report("relax seed loop", static_cast<double>(step) / total);
    const int i = step % 4;
    CurveRelaxation r;
    r.round = step / 4;
    r.curve = i;
    r.length_before = r.length_after = length_of(cm.positions(), out.loop.paths[i]);
    const int vertices_before = cm.num_vertices();
    try {
      Disk disk = cut_open(cm, out.loop, i);
      for (int pass = 0;; ++pass) {
        const auto bad = param::border_degeneracies(disk.pm);
        if (bad.empty()) break;
        if (pass == 4) throw StepFailure{"faces on the border stay degenerate after 4 splitting passes"};
        for (const auto& e : bad) {
          const int h = cm.find_halfedge(disk.global[e[0]], disk.global[e[1]]);
          if (h >= 0) cm.split_edge(h, 0.5);
        }
        disk = cut_open(cm, out.loop, i);
      }
      const param::SquareParam sp = param::parameterize_square(disk.pm, {}, quiet);
      const std::vector<Event> events = walk(disk, sp.uv, options.snap, avoid);

      CutMesh work = cm;
      std::vector<int> path = {out.loop.seeds[i]};
      for (const Event& ev : events) {
        if (ev.b < 0) {
          path.push_back(disk.global[ev.a]);
          continue;
        }
        const int h = work.find_halfedge(disk.global[ev.a], disk.global[ev.b]);
        if (h < 0) throw StepFailure{"a crossed edge vanished while cutting"};
        path.push_back(work.split_edge(h, ev.t));
      }
      path.push_back(out.loop.seeds[(i + 1) % 4]);
      check_curve(work, out.loop, i, path);
      SeedLoop candidate = out.loop;
      candidate.paths[i] = std::move(path);
      const TriMesh work_mesh = work.to_trimesh();
      try {
        seed_patch_of_faces(work_mesh, candidate);
      } catch (const InvalidInput& e) {
        throw StepFailure{std::string("the new curve does not cut the mesh in two: ") + e.what()};
      }
      if (!sides.empty()) {
        const std::vector<int> now = sides_of_vertices(work_mesh, candidate, options.avoid);
        for (std::size_t k = 0; k < sides.size(); ++k)
          if (sides[k] >= 0 && now[k] != sides[k])
            throw StepFailure{"the new curve would leave vertex " + std::to_string(options.avoid[k]) +
                              " (to avoid) on the other side of the loop"};
      }
      cm = std::move(work);
      out.loop = std::move(candidate);
      r.relaxed = true;
      r.length_after = length_of(cm.positions(), out.loop.paths[i]);
    } catch (const StepFailure& e) {
      r.why = e.why;
    } catch (const Error& e) {  // SolverError from the solve (or a precondition it found)
      r.why = std::string("parameterization failed: ") + e.what();
    }
    r.inserted_vertices = cm.num_vertices() - vertices_before;
    if (!r.relaxed)
      context.warn("relax seed loop: curve " + std::to_string(i) + " (round " + std::to_string(r.round) +
                   ") kept as it was: " + r.why);
    out.steps.push_back(std::move(r));
  }
  out.mesh = cm.to_trimesh();
  out.inserted_vertices = out.mesh.num_vertices() - mesh.num_vertices();
  for (int i = 0; i < 4; ++i) out.length_after[i] = length_of(out.mesh.positions, out.loop.paths[i]);
  context.report("relax seed loop", 1.0);
  return out;
}

}  // namespace qs::dissect
