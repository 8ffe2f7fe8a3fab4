#include "qs/mesh/validate.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <sstream>
#include <utility>

#include "qs/core/finite.h"
#include "qs/mesh/connectivity.h"

namespace qs::mesh {

namespace {

constexpr int kMaxIds = 10;
constexpr double kPi = 3.14159265358979323846;

/// Counts elements and keeps the first kMaxIds of them (single ids or vertex pairs).
struct IdList {
  long long count = 0;
  std::vector<long long> ids;
  void add(long long id) {
    if (count < kMaxIds) ids.push_back(id);
    ++count;
  }
  void add_pair(long long a, long long b) {
    if (count < kMaxIds) {
      ids.push_back(a);
      ids.push_back(b);
    }
    ++count;
  }
};

/// "12, 57, ..." or "12-57, 57-90, ..." (pairs), with "..." when not all are shown.
std::string format_ids(const IdList& list, bool pairs) {
  std::string s;
  const std::size_t step = pairs ? 2 : 1;
  for (std::size_t i = 0; i + step <= list.ids.size(); i += step) {
    if (i > 0) s += ", ";
    s += std::to_string(list.ids[i]);
    if (pairs) {
      s += '-';
      s += std::to_string(list.ids[i + 1]);
    }
  }
  if (static_cast<std::size_t>(list.count) * step > list.ids.size()) s += ", ...";
  return s;
}

std::string format_number(double x) {
  std::ostringstream os;
  os.precision(6);
  os << x;
  return os.str();
}

/// Union-find with path halving; the smaller id becomes the root, so results are deterministic.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), 0);
  }
  int find(int x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  void unite(int a, int b) {
    a = find(a);
    b = find(b);
    if (a == b) return;
    if (a < b) std::swap(a, b);
    parent_[a] = b;
  }

 private:
  std::vector<int> parent_;
};

void add_problem(ValidationReport& r, const char* kind, Severity severity, const IdList& list,
                 std::string message) {
  Problem p;
  p.kind = kind;
  p.severity = severity;
  p.count = list.count;
  p.first_ids = list.ids;
  p.message = std::move(message);
  r.problems.push_back(std::move(p));
}

const char* plural(long long n, const char* one, const char* many) { return n == 1 ? one : many; }

Vec3 box_centre(const Box3& b) { return 0.5 * (b.min + b.max); }

/// Bounding box of the positions whose `skip` flag is 0 (all when skip is empty).
Box3 finite_box(const std::vector<Vec3>& positions, const std::vector<char>& skip) {
  Box3 box;
  bool any = false;
  for (std::size_t v = 0; v < positions.size(); ++v) {
    if (!skip.empty() && skip[v]) continue;
    const Vec3& p = positions[v];
    if (!any) {
      box.min = box.max = p;
      any = true;
    } else {
      box.min = box.min.cwiseMin(p);
      box.max = box.max.cwiseMax(p);
    }
  }
  return box;
}

}  // namespace

ValidationResult validate(const TriMesh& input, const ValidateOptions& options) {
  ValidationResult result;
  ValidationReport& report = result.report;
  TriMesh& out = result.mesh;
  const int in_v = input.num_vertices(), in_f = input.num_faces();
  report.input_vertices = in_v;
  report.input_faces = in_f;

  // 1. Faces with an index out of range leave the output; the rest keep their order.
  IdList invalid_index;
  std::vector<int> out_face_source;  // output face -> input face
  out_face_source.reserve(in_f);
  for (int f = 0; f < in_f; ++f) {
    const Tri& t = input.faces[f];
    const bool ok =
        t[0] >= 0 && t[0] < in_v && t[1] >= 0 && t[1] < in_v && t[2] >= 0 && t[2] < in_v;
    if (ok)
      out_face_source.push_back(f);
    else
      invalid_index.add(f);
  }

  // 2. Unreferenced vertices are dropped; the others are renumbered in order.
  std::vector<int>& vertex_map = result.vertex_map;
  vertex_map.assign(in_v, -1);
  for (int f : out_face_source)
    for (int v : input.faces[f]) vertex_map[v] = 0;
  IdList unreferenced;
  std::vector<int> vertex_source;  // output vertex -> input vertex
  vertex_source.reserve(in_v);
  for (int v = 0; v < in_v; ++v) {
    if (vertex_map[v] < 0) {
      unreferenced.add(v);
      continue;
    }
    vertex_map[v] = static_cast<int>(vertex_source.size());
    vertex_source.push_back(v);
  }
  const int nv = static_cast<int>(vertex_source.size());
  out.positions.resize(nv);
  for (int v = 0; v < nv; ++v) out.positions[v] = input.positions[vertex_source[v]];
  out.faces.resize(out_face_source.size());
  for (std::size_t f = 0; f < out_face_source.size(); ++f) {
    const Tri& t = input.faces[out_face_source[f]];
    out.faces[f] = {vertex_map[t[0]], vertex_map[t[1]], vertex_map[t[2]]};
  }
  const int nf = out.num_faces();

  // 3. Non-finite coordinates, and coordinates too large for lengths, areas and volumes to stay
  // finite (|x| > kMaxCoordinate): either makes every later geometric step meaningless.
  IdList non_finite;
  std::vector<char> bad_vertex(nv, 0);
  for (int v = 0; v < nv; ++v)
    if (!usable_position(out.positions[v])) {
      bad_vertex[v] = 1;
      non_finite.add(vertex_source[v]);
    }

  // 4. Faces that repeat a vertex are skipped by every later check.
  IdList repeated;
  std::vector<int> candidates;  // output face ids
  candidates.reserve(nf);
  for (int f = 0; f < nf; ++f) {
    const Tri& t = out.faces[f];
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
      repeated.add(out_face_source[f]);
    else
      candidates.push_back(f);
  }

  // 5. Duplicate faces: bucket by the smallest vertex, sort each bucket by (middle, largest).
  std::vector<char> is_copy(nf, 0);
  std::vector<int> copy_of(nf, -1);
  {
    std::vector<int> start(static_cast<std::size_t>(nv) + 1, 0);
    for (int f : candidates) {
      const Tri& t = out.faces[f];
      ++start[std::min({t[0], t[1], t[2]}) + 1];
    }
    for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<std::pair<std::uint64_t, int>> keys(candidates.size());
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int f : candidates) {
      Tri t = out.faces[f];
      std::sort(t.begin(), t.end());
      keys[fill[t[0]]++] = {
          (static_cast<std::uint64_t>(t[1]) << 32) | static_cast<std::uint32_t>(t[2]), f};
    }
    for (int v = 0; v < nv; ++v) {
      const auto b = keys.begin() + start[v], e = keys.begin() + start[v + 1];
      if (e - b < 2) continue;
      std::sort(b, e);
      for (auto it = b + 1; it != e; ++it) {
        if (it->first != (it - 1)->first) continue;
        is_copy[it->second] = 1;
        copy_of[it->second] =
            copy_of[(it - 1)->second] >= 0 ? copy_of[(it - 1)->second] : (it - 1)->second;
      }
    }
  }
  IdList duplicates;
  std::string duplicate_text;
  std::vector<int> working;  // output face ids checked from here on
  working.reserve(candidates.size());
  for (int f : candidates) {
    if (!is_copy[f]) {
      working.push_back(f);
      continue;
    }
    if (duplicates.count < kMaxIds) {
      if (!duplicate_text.empty()) duplicate_text += ", ";
      duplicate_text += std::to_string(out_face_source[f]) + " (copy of " +
                        std::to_string(out_face_source[copy_of[f]]) + ")";
    }
    duplicates.add(out_face_source[f]);
  }
  if (duplicates.count > kMaxIds) duplicate_text += ", ...";
  const int nw = static_cast<int>(working.size());
  std::vector<Tri> wfaces(nw);
  for (int w = 0; w < nw; ++w) wfaces[w] = out.faces[working[w]];

  // 6. Edges: boundary, manifold, non-manifold, and orientation of manifold ones.
  const EdgeGroups edges = group_halfedges(wfaces, nv);
  const int ne = edges.num_edges();
  auto tail = [&](int h) { return wfaces[h / 3][h % 3]; };
  IdList boundary, non_manifold_edges, misoriented;
  std::vector<std::array<int, 2>> boundary_edges;
  DisjointSets corners(3 * static_cast<std::size_t>(nw));
  for (int e = 0; e < ne; ++e) {
    const int n = edges.size(e);
    const int* hs = &edges.halfedges[edges.offsets[e]];
    const int lo = edges.vertices[e][0], hi = edges.vertices[e][1];
    if (n == 1) {
      boundary.add_pair(vertex_source[lo], vertex_source[hi]);
      boundary_edges.push_back({lo, hi});
    } else if (n > 2) {
      non_manifold_edges.add_pair(vertex_source[lo], vertex_source[hi]);
    } else if (tail(hs[0]) == tail(hs[1])) {
      misoriented.add_pair(vertex_source[lo], vertex_source[hi]);
    }
    // The corners at each end of the edge belong to one fan of that vertex.
    auto corner_at = [&](int h, int v) { return tail(h) == v ? h : Connectivity::next(h); };
    for (int i = 1; i < n; ++i) {
      corners.unite(corner_at(hs[0], lo), corner_at(hs[i], lo));
      corners.unite(corner_at(hs[0], hi), corner_at(hs[i], hi));
    }
  }

  // 7. Non-manifold vertices: more than one fan of corners.
  IdList non_manifold_vertices;
  {
    std::vector<int> fans(nv, 0);
    std::vector<char> root_seen(3 * static_cast<std::size_t>(nw), 0);
    for (int c = 0; c < 3 * nw; ++c) {
      const int r = corners.find(c);
      if (!root_seen[r]) {
        root_seen[r] = 1;
        ++fans[tail(c)];
      }
    }
    for (int v = 0; v < nv; ++v)
      if (fans[v] > 1) non_manifold_vertices.add(vertex_source[v]);
  }

  // 8. Boundary loops: walk boundary edges (undirected) from vertex to vertex.
  if (!boundary_edges.empty()) {
    const int nb = static_cast<int>(boundary_edges.size());
    std::vector<int> start(static_cast<std::size_t>(nv) + 1, 0);
    for (const auto& be : boundary_edges) {
      ++start[be[0] + 1];
      ++start[be[1] + 1];
    }
    for (int v = 0; v < nv; ++v) start[v + 1] += start[v];
    std::vector<int> incident(2 * static_cast<std::size_t>(nb));
    {
      std::vector<int> fill(start.begin(), start.end() - 1);
      for (int i = 0; i < nb; ++i) {
        incident[fill[boundary_edges[i][0]]++] = i;
        incident[fill[boundary_edges[i][1]]++] = i;
      }
    }
    std::vector<int> cursor(start.begin(), start.end() - 1);
    std::vector<char> used(nb, 0);
    for (int i = 0; i < nb; ++i) {
      if (used[i]) continue;
      used[i] = 1;
      const int first = boundary_edges[i][0];
      int cur = boundary_edges[i][1];
      int size = 1;
      while (cur != first) {
        int& k = cursor[cur];
        while (k < start[cur + 1] && used[incident[k]]) ++k;
        if (k == start[cur + 1]) break;  // an open chain (only around non-manifold elements)
        const int j = incident[k];
        used[j] = 1;
        cur = boundary_edges[j][0] == cur ? boundary_edges[j][1] : boundary_edges[j][0];
        ++size;
      }
      report.boundary_loop_sizes.push_back(size);
    }
  }

  // 9. Components, connected through shared vertices of any output face.
  DisjointSets parts(nv);
  for (const Tri& t : out.faces) {
    parts.unite(t[0], t[1]);
    parts.unite(t[0], t[2]);
  }
  std::vector<int> part_of_root(nv, -1);
  IdList components;
  for (int f = 0; f < nf; ++f) {
    const int r = parts.find(out.faces[f][0]);
    if (part_of_root[r] < 0) {
      part_of_root[r] = static_cast<int>(components.count);
      components.add(out_face_source[f]);
    }
  }
  const int num_parts = static_cast<int>(components.count);
  report.components = num_parts;

  // 10. Euler characteristic and genus.
  report.vertices = nv;
  report.faces = nf;
  report.edges = ne;
  report.euler_characteristic = nv - ne + nw;
  const bool closed_manifold_oriented = nw > 0 && boundary.count == 0 &&
                                        non_manifold_edges.count == 0 &&
                                        non_manifold_vertices.count == 0 && misoriented.count == 0;
  IdList genus_problem;
  std::string genus_text;
  if (closed_manifold_oriented) {
    std::vector<long long> chi(num_parts, 0);
    for (int v = 0; v < nv; ++v) chi[part_of_root[parts.find(v)]] += 1;
    for (int e = 0; e < ne; ++e) chi[part_of_root[parts.find(edges.vertices[e][0])]] -= 1;
    for (const Tri& t : wfaces) chi[part_of_root[parts.find(t[0])]] += 1;
    if (num_parts == 1) {
      report.genus = static_cast<int>((2 - chi[0]) / 2);
      if (report.genus != 0) {
        genus_problem.count = report.genus;
        genus_text = "mesh is genus " + std::to_string(report.genus) +
                     " (V-E+F = " + std::to_string(chi[0]) + "); qs needs closed genus-0 meshes";
      }
    } else {
      std::string genera;
      for (int p = 0; p < num_parts; ++p) {
        const long long g = (2 - chi[p]) / 2;
        if (g == 0) continue;
        ++genus_problem.count;
        genera += (genera.empty() ? "" : ", ") + std::to_string(g);
      }
      if (genus_problem.count > 0)
        genus_text = std::to_string(genus_problem.count) + " of " + std::to_string(num_parts) +
                     " components have a non-zero genus (" + genera +
                     "); qs needs closed genus-0 meshes";
    }
  }

  // 11. Geometry: bounding box, zero-area faces, angles.
  const Box3 box = finite_box(out.positions, bad_vertex);
  report.bbox_diagonal = box.diagonal();
  const double zero_area = options.zero_area_relative * report.bbox_diagonal * report.bbox_diagonal;
  IdList zero_area_faces, tiny_angle_faces;
  // Angles are compared through tan = |cross| / dot: the smallest angle of a triangle is at most
  // 60 degrees (dot > 0), and tan is increasing there, so one atan at the end is enough.
  double min_tan = std::numeric_limits<double>::infinity();
  const double tiny_tan = std::tan(std::clamp(options.tiny_angle_degrees, 0.0, 60.0) * kPi / 180.0);
  for (int w = 0; w < nw; ++w) {
    const Tri& t = wfaces[w];
    if (bad_vertex[t[0]] || bad_vertex[t[1]] || bad_vertex[t[2]]) continue;
    const Vec3& a = out.positions[t[0]];
    const Vec3& b = out.positions[t[1]];
    const Vec3& c = out.positions[t[2]];
    const double cross = (b - a).cross(c - a).norm();
    if (0.5 * cross <= zero_area) {
      zero_area_faces.add(out_face_source[working[w]]);
      continue;
    }
    // The smallest angle is opposite the shortest side.
    const double la = (c - b).squaredNorm(), lb = (a - c).squaredNorm(), lc = (b - a).squaredNorm();
    double dot;
    if (la <= lb && la <= lc)
      dot = (b - a).dot(c - a);
    else if (lb <= lc)
      dot = (c - b).dot(a - b);
    else
      dot = (a - c).dot(b - c);
    // dot > 0 for the smallest angle; guard against rounding all the same.
    const double tan_angle = dot > 0 ? cross / dot : std::numeric_limits<double>::max();
    min_tan = std::min(min_tan, tan_angle);
    if (tan_angle < tiny_tan) tiny_angle_faces.add(out_face_source[working[w]]);
  }
  const bool any_angle = min_tan < std::numeric_limits<double>::infinity();
  const double min_angle = std::atan(min_tan);
  report.min_angle_degrees = any_angle ? min_angle * 180.0 / kPi : 0.0;

  // 12. Orientation: a closed, oriented, finite mesh must enclose a positive volume.
  std::string flip_text;
  IdList flipped;
  if (closed_manifold_oriented && non_finite.count == 0) {
    const Vec3 centre = box_centre(box);
    double six_volume = 0;
    for (const Tri& t : wfaces) {
      const Vec3 a = out.positions[t[0]] - centre;
      six_volume += a.dot((out.positions[t[1]] - centre).cross(out.positions[t[2]] - centre));
    }
    report.signed_volume = six_volume / 6.0;
    if (report.signed_volume < 0) {
      for (Tri& t : out.faces) std::swap(t[1], t[2]);
      report.orientation_flipped = true;
      flipped.count = nf;
      flip_text = "mesh was inside out (signed volume " + format_number(report.signed_volume) +
                  "); all " + std::to_string(nf) + " faces were flipped to face outward";
      report.signed_volume = -report.signed_volume;
    }
  }

  // 13. The problems, Fatal first, in the documented order.
  using S = Severity;
  if (nw == 0)
    add_problem(report, "empty", S::Fatal, IdList{1, {}},
                in_f == 0 ? "mesh has no faces"
                          : "mesh has no usable faces (every face has an invalid or repeated "
                            "vertex index)");
  if (invalid_index.count)
    add_problem(report, "invalid_vertex_index", S::Fatal, invalid_index,
                "invalid vertex indices: " + std::to_string(invalid_index.count) + " " +
                    plural(invalid_index.count, "face", "faces") +
                    " (first: " + format_ids(invalid_index, false) + ") use an index outside [0, " +
                    std::to_string(in_v) + "); each index must name an existing vertex");
  if (non_finite.count)
    add_problem(
        report, "non_finite_coordinates", S::Fatal, non_finite,
        "non-finite coordinates: " + std::to_string(non_finite.count) + " " +
            plural(non_finite.count, "vertex", "vertices") +
            " (first: " + format_ids(non_finite, false) +
            ") with a NaN, infinite or too large coordinate; every coordinate must be a finite number of "
            "magnitude at most 1e100");
  if (repeated.count)
    add_problem(report, "repeated_index_faces", S::Fatal, repeated,
                "faces using a vertex twice: " + std::to_string(repeated.count) + " (first: " +
                    format_ids(repeated, false) + "); each face needs three distinct vertices");
  if (duplicates.count)
    add_problem(report, "duplicate_faces", S::Fatal, duplicates,
                "duplicate faces: " + std::to_string(duplicates.count) +
                    " (first: " + duplicate_text +
                    "); each triangle may appear only once, in either orientation");
  if (non_manifold_edges.count)
    add_problem(report, "non_manifold_edges", S::Fatal, non_manifold_edges,
                "non-manifold edges: " + std::to_string(non_manifold_edges.count) +
                    " (first: " + format_ids(non_manifold_edges, true) +
                    "); each edge must have exactly two faces");
  if (non_manifold_vertices.count)
    add_problem(report, "non_manifold_vertices", S::Fatal, non_manifold_vertices,
                "non-manifold vertices: " + std::to_string(non_manifold_vertices.count) +
                    " (first: " + format_ids(non_manifold_vertices, false) +
                    "); the faces around a vertex must form a single fan, not surfaces touching "
                    "at a point");
  if (misoriented.count)
    add_problem(report, "inconsistent_orientation", S::Fatal, misoriented,
                "inconsistently oriented edges: " + std::to_string(misoriented.count) +
                    " (first: " + format_ids(misoriented, true) +
                    "); the two faces of an edge must run along it in opposite directions "
                    "(flip the mis-oriented faces)");
  if (boundary.count) {
    std::string sizes;
    for (std::size_t i = 0; i < report.boundary_loop_sizes.size() && i < kMaxIds; ++i)
      sizes += (i ? ", " : "") + std::to_string(report.boundary_loop_sizes[i]);
    if (report.boundary_loop_sizes.size() > kMaxIds) sizes += ", ...";
    const auto loops = static_cast<long long>(report.boundary_loop_sizes.size());
    add_problem(report, "boundary_edges", S::Fatal, boundary,
                "boundary edges: " + std::to_string(boundary.count) + " in " +
                    std::to_string(loops) + " " + plural(loops, "loop", "loops") + " of " + sizes +
                    " edges (first: " + format_ids(boundary, true) +
                    "); qs needs a closed mesh (fill the holes)");
  }
  if (num_parts > 1)
    add_problem(report, "multiple_components", S::Fatal, components,
                "mesh has " + std::to_string(num_parts) +
                    " components (first faces: " + format_ids(components, false) +
                    "); qs needs one connected surface (split the parts into separate files)");
  if (genus_problem.count) {
    if (options.allow_any_genus)  // reported, not rejected (qs-dfi)
      genus_text = genus_text.substr(0, genus_text.find(';')) + "; accepted (any genus allowed)";
    add_problem(report, "genus", options.allow_any_genus ? S::Note : S::Fatal, genus_problem, genus_text);
  }
  if (unreferenced.count)
    add_problem(report, "unreferenced_vertices", S::Note, unreferenced,
                "unreferenced vertices: " + std::to_string(unreferenced.count) +
                    " (first: " + format_ids(unreferenced, false) +
                    ") are used by no face; dropped, the others renumbered");
  if (report.orientation_flipped)
    add_problem(report, "orientation_flipped", S::Note, flipped, flip_text);
  if (zero_area_faces.count)
    add_problem(report, "zero_area_faces", S::Warning, zero_area_faces,
                "zero-area faces: " + std::to_string(zero_area_faces.count) +
                    " (first: " + format_ids(zero_area_faces, false) + ") with area <= " +
                    format_number(zero_area) + "; they carry no shape and may upset later stages");
  if (tiny_angle_faces.count)
    add_problem(report, "tiny_angles", S::Warning, tiny_angle_faces,
                "faces with an angle below " + format_number(options.tiny_angle_degrees) +
                    " degrees: " + std::to_string(tiny_angle_faces.count) + " (first: " +
                    format_ids(tiny_angle_faces, false) + "); the smallest angle is " +
                    format_number(report.min_angle_degrees) + " degrees");

  report.accepted = std::none_of(report.problems.begin(), report.problems.end(),
                                 [](const Problem& p) { return p.severity == Severity::Fatal; });
  return result;
}

std::string format_report(const std::string& name, const ValidationReport& r) {
  std::ostringstream os;
  os << name << ": " << r.vertices << " vertices, " << r.faces << " faces, " << r.edges
     << " edges\n";
  if (r.input_vertices != r.vertices || r.input_faces != r.faces)
    os << "  input: " << r.input_vertices << " vertices, " << r.input_faces << " faces\n";
  os << "  components: " << r.components << "\n";
  os << "  genus: " << (r.genus >= 0 ? std::to_string(r.genus) : std::string("undefined"))
     << " (V-E+F = " << r.euler_characteristic << ")\n";
  os << "  boundary loops: ";
  if (r.boundary_loop_sizes.empty()) {
    os << "none\n";
  } else {
    os << r.boundary_loop_sizes.size() << " (edges:";
    for (std::size_t i = 0; i < r.boundary_loop_sizes.size(); ++i) {
      if (i == kMaxIds) {
        os << " ...";
        break;
      }
      os << " " << r.boundary_loop_sizes[i];
    }
    os << ")\n";
  }
  os << "  min angle: " << format_number(r.min_angle_degrees) << " degrees\n";
  os << "  bounding box diagonal: " << format_number(r.bbox_diagonal) << "\n";
  std::string reasons;
  for (const Problem& p : r.problems) {
    const char* label = p.severity == Severity::Fatal     ? "error"
                        : p.severity == Severity::Warning ? "warning"
                                                          : "note";
    os << "  " << label << " [" << p.kind << "]: " << p.message << "\n";
    if (p.severity == Severity::Fatal) reasons += (reasons.empty() ? "" : ", ") + p.kind;
  }
  if (r.accepted)
    os << "accepted\n";
  else
    os << "rejected: " << (reasons.empty() ? std::string("not validated") : reasons) << "\n";
  return os.str();
}

const Problem* find_problem(const ValidationReport& report, std::string_view kind) {
  for (const Problem& p : report.problems)
    if (p.kind == kind) return &p;
  return nullptr;
}

double signed_volume(const TriMesh& mesh) {
  const Vec3 centre = box_centre(finite_box(mesh.positions, {}));
  double six_volume = 0;
  for (const Tri& t : mesh.faces) {
    const Vec3 a = mesh.positions[t[0]] - centre;
    six_volume += a.dot((mesh.positions[t[1]] - centre).cross(mesh.positions[t[2]] - centre));
  }
  return six_volume / 6.0;
}

}  // namespace qs::mesh
