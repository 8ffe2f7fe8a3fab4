// qs-family: test data with exact ground truth.
//   qs-family generate  -> N smooth shapes with limbs, each with its own tessellation, landmarks
//                          and a map file to the common parameter sphere.
//   qs-family retessellate MESH -> a new tessellation of the same surface, with each vertex's
//                          exact origin on MESH (a "surface" map file) and transferred landmarks.
//   qs-family pose MESH -> MESH in another pose (limbs bent or turned as rigidly as possible), with
//                          the same vertices and faces (the map is vertex i <-> vertex i),
//                          landmarks for both, and optionally the posed mesh re-tessellated.
//
// Exit codes: 0 written; 1 usage (an option out of range, an output that is an input, a name the
// map file cannot hold, a request over --max-memory or the free disk); 2 invalid input (a rejected
// mesh, bad landmarks); 3 i/o; 4 the re-tessellation is not a usable mesh, or no limb can be
// posed; 70 internal. Every output is staged and moved into place only when everything was made.

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "qs/pipeline/pipeline.h"
#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/core/output_folder.h"
#include "qs/core/parallel.h"
#include "qs/family/family.h"
#include "qs/family/pose.h"
#include "qs/family/retessellate.h"
#include "qs/family/surface_map.h"
#include "qs/io/write_mesh.h"
#include "qs/metro/metro.h"
#include "resource_limits.h"
#include "tool_main.h"

namespace fs = std::filesystem;

namespace {

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

std::string shown(const std::string& s) { return qs::json_strict::printable(s); }

// ---------------------------------------------------------------------------------------------
// Options: every number is checked for form, range and finiteness while parsing (a usage error,
// before any work); nothing wraps ("--seed -1" is refused, not 2^64 - 1).

CLI::Validator finite_in(double lo, double hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) -> std::string {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || end != text.c_str() + text.size())
          return "expected a number, got \"" + shown(text) + "\"";
        if (!std::isfinite(v)) return "Value " + shown(text) + " is not a finite number";
        if (v < lo || v > hi) return "Value " + text + " not in range " + num(lo) + " to " + num(hi);
        return {};
      },
      "FLOAT in [" + num(lo) + " - " + num(hi) + "]");
}

// A decimal integer without sign or exponent; false when `text` is not one or exceeds `hi`.
bool decimal_in(const std::string& text, unsigned long long hi, unsigned long long& out) {
  if (text.empty() || text.size() > 20) return false;
  for (char c : text)
    if (c < '0' || c > '9') return false;
  errno = 0;
  out = std::strtoull(text.c_str(), nullptr, 10);
  return errno != ERANGE && out <= hi;
}

CLI::Validator seed_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        unsigned long long v = 0;
        if (!decimal_in(text, UINT64_MAX, v))
          return "Value " + shown(text) + ": expected a whole number in [0, 18446744073709551615]";
        return {};
      },
      "UINT in [0 - 18446744073709551615]");
}

std::uint64_t seed_value(const std::string& text) {
  unsigned long long v = 0;
  decimal_in(text, UINT64_MAX, v);  // checked while parsing
  return v;
}

// Faces of a generated shape: even, 200..2,000,000 (a closed genus-0 mesh has F = 2V - 4).
CLI::Validator generated_faces_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        unsigned long long v = 0;
        if (!decimal_in(text, 2000000, v) || v < 200 || v % 2 != 0)
          return "Value " + shown(text) + ": expected an even count in [200, 2000000]";
        return {};
      },
      "EVEN INT in [200 - 2000000]");
}

// Target faces of a re-tessellation: 0 (the input's) or 100..kMaxFaces.
CLI::Validator target_faces_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        unsigned long long v = 0;
        if (!decimal_in(text, qs::family::kMaxFaces, v) || (v != 0 && v < 100))
          return "Value " + shown(text) + ": expected 0 (the input's) or a count in [100, " +
                 std::to_string(qs::family::kMaxFaces) + "]";
        return {};
      },
      "INT: 0 or [100 - 2000000]");
}

CLI::Validator limbs_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (text != "0" && text != "4" && text != "5" && text != "6")
          return "Value " + shown(text) + ": expected 4, 5 or 6 (or 0: chosen by the seed)";
        return {};
      },
      "0, 4, 5 or 6");
}

// ---------------------------------------------------------------------------------------------
// Estimates, made before any work, from runs measured with /usr/bin/time -v (CPU time of one
// thread, peak resident memory; docs/tools/qs-family.md has the figures), rounded up.
//   generate, one shape: 0.25 / 1.0 / 4.7 / 20.8 s and 8 / 12 / 30 / 102 MB at 8k / 32k / 128k /
//     512k faces: linear, about 40 us and 190 B a face.
//   retessellate: 8k -> 32k / 128k / 512k faces 0.9 / 3.5 / 15.3 s, 24 / 74 / 264 MB; 128k / 512k
//     -> 8k faces 3.1 / 18.6 s, 72 / 281 MB: about 35 us and 550 B a face, input and output.
//   --keep-shape remeshes 9 times the faces first: 8k -> 8k / 16k faces 3.6 / 9.4 s, 28 / 48 MB;
//     its time per face grows about as the 0.4th power of the faces.

constexpr double kBaseBytes = 32e6;             // the process, CGAL, buffers
constexpr double kGenerateBytesPerFace = 250;   // one shape being made and written
constexpr double kGenerateSecondsPerFace = 45e-6;
constexpr double kFileBytesPerFace = 95;        // a shape's mesh and map file (OBJ: 52 + 33 B)
constexpr double kRetessBytesPerFace = 600;     // input and output faces in CGAL's remesher
constexpr double kRetessSecondsPerFace = 40e-6;

std::string duration_text(double seconds) {
  char buf[64];
  if (seconds < 90)
    std::snprintf(buf, sizeof buf, "%.0f s", std::max(1.0, seconds));
  else if (seconds < 5400)
    std::snprintf(buf, sizeof buf, "%.0f min", seconds / 60);
  else
    std::snprintf(buf, sizeof buf, "%.1f h", seconds / 3600);
  return buf;
}

std::string bytes_text(double bytes) {
  char buf[64];
  if (bytes < 1e9)
    std::snprintf(buf, sizeof buf, "%.0f MB", std::max(1.0, bytes / 1e6));
  else
    std::snprintf(buf, sizeof buf, "%.1f GB", bytes / 1e9);
  return buf;
}

int cores() { return static_cast<int>(std::max(1u, std::thread::hardware_concurrency())); }

// \throws UsageError when the files would not fit on the file system that holds `target`.
void check_disk(double bytes, const fs::path& target, const std::string& what) {
  std::error_code ec;
  fs::path existing = fs::absolute(target, ec);
  while (!existing.empty() && !fs::exists(existing, ec) && existing != existing.parent_path())
    existing = existing.parent_path();
  const fs::space_info space = fs::space(existing, ec);
  if (ec) return;  // unknown: the writes will say
  if (bytes > static_cast<double>(space.available))
    throw qs::UsageError(what + " needs about " + bytes_text(bytes) + " of disk for its files, more than the " +
                         bytes_text(static_cast<double>(space.available)) + " free in " + shown(existing.string()));
}

void say_estimate(bool quiet, double seconds, double bytes, const std::string& what) {
  if (quiet || seconds < 10) return;
  std::cout << "qs-family: " << what << ": about " << duration_text(seconds) << " and " << qs::tools::gib_text(bytes)
            << " of memory (estimated)" << std::endl;
}

// Peak memory and time of one re-tessellation from `in_faces` faces to about `faces` faces.
struct RetessEstimate {
  double bytes = 0, seconds = 0;
};
RetessEstimate estimate_retessellation(int in_faces, const qs::family::RetessellateOptions& opt, bool report) {
  const double target = opt.faces > 0 ? opt.faces : in_faces;
  const double work = opt.keep_shape ? 9 * target : target;  // the finer remesh, then simplified back
  const double growth = opt.keep_shape ? std::pow(std::max(1.0, work / 72000), 0.4) : 1.0;
  RetessEstimate e;
  e.bytes = kBaseBytes + kRetessBytesPerFace * (in_faces + work);
  e.seconds = kRetessSecondsPerFace * (in_faces + work * growth) * opt.iterations / 3.0;
  if (report) e.seconds += kRetessSecondsPerFace * (in_faces + target) / 2;  // the two-sided distance
  return e;
}

// ---------------------------------------------------------------------------------------------
// generate

int run_generate(const qs::family::FamilyOptions& opt, const std::string& outdir, const std::string& format,
                 int threads, double max_memory, bool quiet) {
  // Shapes are made in batches of the thread count; a batch that would not fit in --max-memory
  // is made on fewer threads (the output does not depend on the count).
  qs::Context ctx;
  const double per_shape = kGenerateBytesPerFace * opt.faces;
  const std::string what = "generate -n " + std::to_string(opt.shapes) + " --faces " + std::to_string(opt.faces);
  qs::tools::check_memory(kBaseBytes + per_shape, max_memory, what + " (one shape at a time)");
  const double limit = max_memory * 1024.0 * 1024.0 * 1024.0;
  const int fit = static_cast<int>(std::max(1.0, std::floor((limit - kBaseBytes) / per_shape)));
  ctx.threads = std::min({qs::thread_count(threads, ctx), opt.shapes, fit});
  const double bytes = kBaseBytes + per_shape * ctx.threads;
  const double seconds =
      kGenerateSecondsPerFace * opt.faces * opt.shapes / std::min(ctx.threads, cores());
  check_disk((kFileBytesPerFace * opt.faces + 4096.0) * opt.shapes, outdir, what);
  say_estimate(quiet, seconds, bytes, what + " on " + std::to_string(ctx.threads) + " threads");

  qs::OutputFolder folder(outdir);
  const fs::path dir(outdir), staging = folder.staging();
  nlohmann::json shapes = nlohmann::json::array();
  std::vector<std::string> lines;
  auto write_shape = [&](qs::family::FamilyShape&& s) {
    const std::string mesh_file = s.name + "." + format;
    qs::io::write_mesh(staging / mesh_file, s.mesh);
    qs::write_file_atomically(staging / (s.name + ".landmarks.json"), qs::family::landmarks_json(s));
    qs::family::SurfaceMap map;
    map.domain = qs::family::MapDomain::Sphere;
    map.sphere = std::move(s.parameters);
    qs::family::write_surface_map(staging / (s.name + ".map.json"), map);
    shapes.push_back({{"name", s.name},
                      {"mesh", mesh_file},
                      {"landmarks", s.name + ".landmarks.json"},
                      {"map", s.name + ".map.json"},
                      {"vertices", s.mesh.num_vertices()},
                      {"faces", s.mesh.num_faces()}});
    lines.push_back((dir / mesh_file).string() + ": " + std::to_string(s.mesh.num_vertices()) + " vertices, " +
                    std::to_string(s.mesh.num_faces()) + " faces, " + std::to_string(s.features.size()) +
                    " features");
  };
  const qs::family::Family fam = qs::family::generate_family(opt, ctx, write_shape);
  nlohmann::json doc = {{"format", "qs-family"},
                        {"version", 1},
                        {"seed", opt.seed},
                        {"shapes", opt.shapes},
                        {"faces", opt.faces},
                        {"limbs", fam.limbs},
                        {"variation", opt.variation},
                        {"features", fam.limb_names},
                        {"meshes", shapes}};
  qs::write_file_atomically(staging / "family.json", doc.dump(2) + "\n");
  folder.commit();
  if (!quiet)
    for (const auto& line : lines) std::cout << line << "\n";
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Outputs of retessellate and pose: a mesh file and files beside it, checked before any work.

// Where the map file of `output` finds `ref_file`: relative to the map's folder, else absolute.
std::string map_reference(const std::string& ref_file, const fs::path& output) {
  std::error_code ec;
  const fs::path abs_in = fs::absolute(ref_file), abs_dir = fs::absolute(output).parent_path();
  const fs::path rel = fs::relative(abs_in, abs_dir, ec);
  return ec || rel.empty() ? abs_in.string() : rel.string();
}

// \throws UsageError when the map file could not hold the path to `ref_file` (JSON is UTF-8).
void check_map_reference(const std::string& ref_file, const fs::path& output) {
  const std::string ref = map_reference(ref_file, output);
  if (!qs::json_strict::is_clean_text(ref))
    throw qs::UsageError(shown(ref_file) + ": the map file records this mesh's path (\"" + shown(ref) +
                         "\" from the output's folder) as JSON text, which must be UTF-8 without control "
                         "characters; rename the file or folder, or write the output where the path is UTF-8");
}

// `output` must name a mesh file (.obj .off .ply) that is not a folder.
void check_mesh_output(const fs::path& output) {
  std::string ext = output.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (!output.has_filename() || (ext != ".obj" && ext != ".off" && ext != ".ply"))
    throw qs::UsageError("-o " + shown(output.string()) + ": expected a mesh file name ending in .obj, .off or .ply");
}

// The mesh, and the landmark file that will be read with it (given, else found beside it).
std::vector<fs::path> input_files(const std::string& input, const std::optional<std::string>& landmark_file) {
  std::vector<fs::path> inputs{input};
  if (landmark_file)
    inputs.emplace_back(*landmark_file);
  else if (const auto beside = qs::landmarks::find_landmarks_beside(input))
    inputs.push_back(*beside);
  return inputs;
}

// outputs[0] is the file named by -o, the others go beside it.
void check_outputs(const std::vector<fs::path>& outputs, const std::vector<fs::path>& inputs) {
  for (const auto& o : outputs) {
    std::error_code ec;
    if (fs::is_directory(o, ec))
      throw qs::IoError(shown(o.string()) + ": is a folder; -o " + shown(outputs.front().string()) +
                        " needs to write a file there");
    try {
      qs::check_not_an_input(o, inputs, "-o");
    } catch (const qs::UsageError&) {
      if (o == outputs.front()) throw;
      throw qs::UsageError("-o " + shown(outputs.front().string()) + " would also write " + shown(o.string()) +
                           ", which is an input of this run; write the output somewhere else or under another name");
    }
  }
}

fs::path folder_of(const fs::path& output) { return output.has_parent_path() ? output.parent_path() : fs::path("."); }

// A re-tessellation of `ref` (the mesh of file `ref_file`) made but not yet written, with its map
// onto the reference and the reference's landmarks carried over.
struct RetessellationOut {
  qs::family::Retessellation r;
  qs::family::SurfaceMap map;
  std::string landmarks_text;  // empty without landmarks
};

RetessellationOut make_retessellation(const qs::TriMesh& ref, const std::optional<qs::landmarks::Landmarks>& lms,
                                      const std::string& ref_file, const qs::family::RetessellateOptions& opt,
                                      const std::string& output) {
  RetessellationOut o;
  o.r = qs::family::retessellate(ref, opt);
  const qs::family::Retessellation& r = o.r;
  qs::family::SurfaceMap& map = o.map;
  map.domain = qs::family::MapDomain::Surface;
  map.reference = map_reference(ref_file, output);
  map.reference_vertices = ref.num_vertices();
  map.reference_faces = ref.num_faces();
  map.origins = r.origins;
  // Landmarks: each point of the input goes to its closest point of the new tessellation.
  if (lms) {
    const qs::metro::SurfaceDistance target(r.mesh, "retessellation");
    auto refer = [&](const qs::landmarks::Landmark& l) {
      const qs::Vec3 p = qs::landmarks::position_of(ref, l.where);
      const auto c = target.closest(p);
      const qs::Tri& t = r.mesh.faces[c.face];
      const qs::Vec3 a = r.mesh.positions[t[0]], e0 = r.mesh.positions[t[1]] - a, e1 = r.mesh.positions[t[2]] - a;
      const qs::Vec3 q = c.point - a;
      const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1), d20 = q.dot(e0), d21 = q.dot(e1);
      const double den = d00 * d11 - d01 * d01;
      double v = den > 0 ? (d11 * d20 - d01 * d21) / den : 0, w = den > 0 ? (d00 * d21 - d01 * d20) / den : 0;
      v = std::clamp(v, 0.0, 1.0);
      w = std::clamp(w, 0.0, 1.0 - v);
      return "{\"face\": " + std::to_string(c.face) + ", \"bary\": [" + num(1 - v - w) + ", " + num(v) + ", " +
             num(w) + "]}";
    };
    std::string& text = o.landmarks_text;
    text = "{\n";
    if (!lms->seeds.empty()) {
      text += "  \"seeds\": [\n";
      for (std::size_t i = 0; i < lms->seeds.size(); ++i)
        text += "    " + refer(lms->seeds[i]) + (i + 1 < lms->seeds.size() ? ",\n" : "\n");
      text += "  ]" + std::string(lms->features.empty() ? "\n" : ",\n");
    }
    if (!lms->features.empty()) {
      text += "  \"features\": {\n";
      for (std::size_t i = 0; i < lms->features.size(); ++i)
        text += "    " + nlohmann::json(lms->features[i].name).dump() + ": " + refer(lms->features[i]) +
                (i + 1 < lms->features.size() ? ",\n" : "\n");
      text += "  }\n";
    }
    text += "}\n";
  }
  return o;
}

// The files of a re-tessellation whose final name is `output`, written into `staging`.
void write_retessellation(const RetessellationOut& o, const fs::path& staging, const fs::path& output) {
  const fs::path base = staging / output.stem();
  qs::io::write_mesh(staging / output.filename(), o.r.mesh);
  qs::family::write_surface_map(base.string() + ".map.json", o.map);
  if (!o.landmarks_text.empty()) qs::write_file_atomically(base.string() + ".landmarks.json", o.landmarks_text);
}

// What a re-tessellation did, said once its files are in place.
std::string retessellation_report(const RetessellationOut& o, const qs::TriMesh& ref, const std::string& ref_file,
                                  const std::string& output) {
  // The new surface is the input's only at the vertices: its faces are chords, so fine detail
  // (fingers, say) loses area and shape. Said, since a map between the two is then not an
  // isometry, and the ground truth between the vertices is only as good as the chords.
  const fs::path out(output);
  const fs::path base = out.parent_path() / out.stem();
  const double in_area = qs::surface_area(ref);
  char change[64];
  std::snprintf(change, sizeof change, "%+.2f%%", in_area > 0 ? 100 * (qs::surface_area(o.r.mesh) / in_area - 1) : 0.0);
  const qs::metro::MetroResult gap = qs::metro::metro(ref, o.r.mesh);
  char hausdorff[64];
  std::snprintf(hausdorff, sizeof hausdorff, "%.3f%%", gap.diagonal > 0 ? 100 * gap.max / gap.diagonal : 0.0);
  return output + ": " + std::to_string(o.r.mesh.num_vertices()) + " vertices, " +
         std::to_string(o.r.mesh.num_faces()) + " faces, area " + change + " against the input, surfaces at most " +
         hausdorff + " of the diagonal apart; origins on " + ref_file + " in " + base.string() + ".map.json" +
         (o.landmarks_text.empty() ? "" : "; landmarks in " + base.string() + ".landmarks.json") + "\n";
}

// Origins and landmarks refer to vertices and faces of the file as written: a mesh that
// validation changes (unreferenced vertices, faces turned) is refused.
void require_as_written(const qs::pipeline::Input& in, const std::string& input) {
  if (in.valid.vertex_map.size() != in.read.mesh.positions.size() || in.valid.report.orientation_flipped ||
      in.valid.mesh.num_vertices() != in.read.mesh.num_vertices())
    throw qs::InvalidInput(input + ": the mesh has unreferenced vertices or faces inward; origins would not refer "
                           "to the file as written (clean it first, e.g. by writing what qs-inspect accepts)");
}

// The re-tessellation's face-count rule, checked before the estimate.
void check_target_faces(int in_faces, const qs::family::RetessellateOptions& opt, const std::string& input) {
  if (opt.faces == 0 && in_faces > qs::family::kMaxFaces)
    throw qs::InvalidInput(input + ": the mesh has " + std::to_string(in_faces) + " faces; give --faces (at most " +
                           std::to_string(qs::family::kMaxFaces) + ")");
}

int run_retessellate(const std::string& input, const std::optional<std::string>& landmark_file,
                     const qs::family::RetessellateOptions& opt, const std::string& output, double max_memory,
                     bool quiet) {
  const fs::path out(output);
  const fs::path base = out.parent_path() / out.stem();
  check_mesh_output(out);
  std::vector<fs::path> inputs = input_files(input, landmark_file);
  const std::vector<fs::path> outputs{out, base.string() + ".map.json", base.string() + ".landmarks.json"};
  check_outputs(outputs, inputs);
  check_map_reference(input, out);
  const qs::pipeline::Input in = qs::pipeline::load_input(input, landmark_file);
  require_as_written(in, input);
  const int in_faces = in.valid.mesh.num_faces();
  check_target_faces(in_faces, opt, input);
  const RetessEstimate e = estimate_retessellation(in_faces, opt, !quiet);
  const std::string what = "retessellate" + std::string(opt.keep_shape ? " --keep-shape" : "") + " of " +
                           std::to_string(in_faces) + " faces to " +
                           std::to_string(opt.faces > 0 ? opt.faces : in_faces);
  qs::tools::check_memory(e.bytes, max_memory, what);
  check_disk(kFileBytesPerFace * (opt.faces > 0 ? opt.faces : in_faces), folder_of(out), what);
  say_estimate(quiet, e.seconds, e.bytes, what);

  qs::OutputFolder folder(folder_of(out), out.filename().string());
  const RetessellationOut o = make_retessellation(in.valid.mesh, in.landmarks, input, opt, output);
  write_retessellation(o, folder.staging(), out);
  const std::string report = quiet ? std::string() : retessellation_report(o, in.valid.mesh, input, output);
  folder.commit();
  std::cout << report;
  return 0;
}

// ---------------------------------------------------------------------------------------------
// pose

// A landmark as a reference of the mesh file: its vertex, else its face and weights.
std::string landmark_ref(const qs::landmarks::Landmark& l) {
  if (l.vertex >= 0) return std::to_string(l.vertex);
  return "{\"face\": " + std::to_string(l.where.face) + ", \"bary\": [" + num(l.where.bary[0]) + ", " +
         num(l.where.bary[1]) + ", " + num(l.where.bary[2]) + "]}";
}

struct PoseArgs {
  qs::family::PoseOptions opt;
  std::string seed = "1";
  std::string pose_name = "mixed";
  bool retessellate = false;
  qs::family::RetessellateOptions ropt;
};

// Measured: 8k / 128k / 512k faces 0.18 / 13 / 174 s and 10 / 75 / 274 MB; the limbs' rigid
// solves (CGAL Surface_mesh_deformation) grow as about the 1.7th power of the faces.
constexpr double kPoseBytesPerFace = 900;
double pose_seconds(int faces) { return 0.18 * std::pow(std::max(1.0, faces / 8000.0), 1.7); }

int run_pose(const std::string& input, const std::optional<std::string>& landmark_file, const PoseArgs& args,
             const std::string& output, double max_memory, bool quiet) {
  const fs::path out(output);
  const fs::path base = out.parent_path() / out.stem();
  const std::string retess_file = base.string() + "_r" + out.extension().string();
  check_mesh_output(out);
  if (!(args.opt.min_angle_deg <= args.opt.max_angle_deg))
    throw qs::UsageError("--min-angle " + num(args.opt.min_angle_deg) + " is larger than --max-angle " +
                         num(args.opt.max_angle_deg));
  std::vector<fs::path> inputs = input_files(input, landmark_file);
  std::vector<fs::path> outputs{out, base.string() + ".landmarks.json", base.string() + ".source.landmarks.json",
                                base.string() + ".pose.json"};
  if (args.retessellate) {
    const fs::path r(retess_file);
    const fs::path rbase = r.parent_path() / r.stem();
    outputs.insert(outputs.end(), {r, rbase.string() + ".map.json", rbase.string() + ".landmarks.json"});
    check_map_reference(output, r);
  }
  check_outputs(outputs, inputs);
  const qs::pipeline::Input in = qs::pipeline::load_input(input, landmark_file);
  require_as_written(in, input);
  const int faces = in.valid.mesh.num_faces();
  RetessEstimate e{kBaseBytes + kPoseBytesPerFace * faces, pose_seconds(faces)};
  if (args.retessellate) {
    check_target_faces(faces, args.ropt, output);
    const RetessEstimate r = estimate_retessellation(faces, args.ropt, !quiet);
    e.bytes = std::max(e.bytes, r.bytes + 64.0 * faces);  // the pose is kept while it is re-tessellated
    e.seconds += r.seconds;
  }
  const std::string what = "pose of " + std::to_string(faces) + " faces" +
                           (args.retessellate ? std::string(" and its re-tessellation") : std::string());
  qs::tools::check_memory(e.bytes, max_memory, what);
  check_disk(kFileBytesPerFace * faces * (args.retessellate ? 2 : 1), folder_of(out), what);
  say_estimate(quiet, e.seconds, e.bytes, what);

  qs::family::PoseOptions opt = args.opt;
  opt.seed = seed_value(args.seed);
  opt.kind = args.pose_name == "bend"    ? qs::family::PoseKind::Bend
             : args.pose_name == "twist" ? qs::family::PoseKind::Twist
                                         : qs::family::PoseKind::Mixed;
  const qs::family::Pose pose = qs::family::pose_mesh(in.valid.mesh, opt);
  // Landmarks: the input's (found beside it or given), else chosen at the extremities. The same
  // references hold on both meshes, which share their vertices and faces.
  std::string lm_text = "{\n  \"seeds\": [";
  std::string origin;
  if (in.landmarks && in.landmarks->seeds.size() == 4) {
    origin = in.landmark_file;
    for (std::size_t i = 0; i < 4; ++i) lm_text += (i ? ", " : "") + landmark_ref(in.landmarks->seeds[i]);
    lm_text += "]";
    if (!in.landmarks->features.empty()) {
      lm_text += ",\n  \"features\": {\n";
      for (std::size_t i = 0; i < in.landmarks->features.size(); ++i)
        lm_text += "    " + nlohmann::json(in.landmarks->features[i].name).dump() + ": " +
                   landmark_ref(in.landmarks->features[i]) + (i + 1 < in.landmarks->features.size() ? ",\n" : "\n");
      lm_text += "  }";
    }
  } else {
    if (in.landmarks)
      throw qs::InvalidInput(in.landmark_file + ": pose needs 4 seeds in the landmarks (or no landmark file, to "
                             "choose them at the extremities)");
    origin = "extremities";
    const qs::family::PoseLandmarks lm = qs::family::choose_landmarks(in.valid.mesh);
    for (std::size_t i = 0; i < 4; ++i) lm_text += (i ? ", " : "") + std::to_string(lm.seeds[i]);
    lm_text += "],\n  \"features\": {\n";
    for (std::size_t i = 0; i < lm.features.size(); ++i)
      lm_text += "    " + nlohmann::json(lm.features[i].first).dump() + ": " + std::to_string(lm.features[i].second) +
                 (i + 1 < lm.features.size() ? ",\n" : "\n");
    lm_text += "  }";
  }
  lm_text += "\n}\n";
  std::optional<RetessellationOut> retess;
  if (args.retessellate) {
    const qs::mesh::ValidationResult posed_valid = qs::mesh::validate(pose.mesh);
    const qs::landmarks::Landmarks posed_lm =
        qs::landmarks::parse_landmarks(lm_text, qs::landmarks::LandmarkFormat::Json, output, posed_valid);
    retess = make_retessellation(pose.mesh, posed_lm, output, args.ropt, retess_file);
  }
  nlohmann::json limbs = nlohmann::json::array();
  for (const auto& l : pose.limbs)
    limbs.push_back({{"tip", l.tip},
                     {"radius", l.radius},
                     {"pivot", {l.pivot.x(), l.pivot.y(), l.pivot.z()}},
                     {"axis", {l.axis.x(), l.axis.y(), l.axis.z()}},
                     {"angle_degrees", l.angle_deg},
                     {"kind", l.twist ? "twist" : "bend"},
                     {"handle_vertices", l.handle.size()},
                     {"moved_vertices", l.region.size()}});
  const nlohmann::json doc = {{"format", "qs-pose"},
                              {"version", 1},
                              {"input", shown(input)},
                              {"seed", opt.seed},
                              {"pose", args.pose_name},
                              {"landmarks", origin == "extremities" ? origin : shown(origin)},
                              {"limbs_found", pose.limbs_found},
                              {"limbs_dropped", pose.limbs_dropped},
                              {"input_self_intersections", pose.input_self_intersections},
                              {"limbs", limbs}};
  qs::OutputFolder folder(folder_of(out), out.filename().string());
  const fs::path staged = folder.staging() / out.stem();
  qs::io::write_mesh(folder.staging() / out.filename(), pose.mesh);
  qs::write_file_atomically(staged.string() + ".landmarks.json", lm_text);
  qs::write_file_atomically(staged.string() + ".source.landmarks.json", lm_text);
  qs::write_file_atomically(staged.string() + ".pose.json", doc.dump(2) + "\n");
  std::string report;
  if (retess) {
    write_retessellation(*retess, folder.staging(), retess_file);
    if (!quiet) report = retessellation_report(*retess, pose.mesh, output, retess_file);
  }
  folder.commit();
  if (!quiet) {
    std::cout << output << ": " << pose.mesh.num_vertices() << " vertices, the input's " << pose.mesh.num_faces()
              << " faces; " << pose.limbs.size() << " of " << pose.limbs_found << " limbs posed (";
    for (std::size_t k = 0; k < pose.limbs.size(); ++k) {
      char buf[80];
      std::snprintf(buf, sizeof buf, "%s%s %+.0f deg at vertex %d", k ? ", " : "",
                    pose.limbs[k].twist ? "turned" : "bent", pose.limbs[k].angle_deg, pose.limbs[k].tip);
      std::cout << buf;
    }
    std::cout << "); landmarks (" << origin << ") in " << base.string() << ".landmarks.json and, for " << input
              << ", " << base.string() << ".source.landmarks.json; the map is vertex i <-> vertex i\n"
              << report;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Test data with exact ground truth for the correspondence benchmark (docs/correspondence.md).\n"
               "Exit codes: 0 written, 1 usage (or a request over --max-memory), 2 invalid input, 3 i/o, "
               "4 unusable re-tessellation or no limb posed.",
               "qs-family"};
  app.require_subcommand(1);
  qs::family::FamilyOptions fopt;
  std::string outdir, format = "obj", seed_text = "1";
  bool quiet = false;
  int threads = 0;
  double max_memory = qs::tools::kDefaultMaxMemoryGiB;
  auto* gen = app.add_subcommand("generate", "N smooth genus-0 shapes with limbs, own tessellations, landmarks "
                                             "and map files to a common parameter sphere");
  gen->add_option("-n,--shapes", fopt.shapes, "Number of shapes (1..256)")->capture_default_str()->check(CLI::Range(1, 256));
  gen->add_option("--seed", seed_text, "Seed of the family (the same seed gives the same files)")
      ->capture_default_str()
      ->check(seed_check());
  gen->add_option("--faces", fopt.faces, "Faces per shape (even, 200..2000000)")
      ->capture_default_str()
      ->check(generated_faces_check());
  gen->add_option("--limbs", fopt.limbs, "4 legs, 5 with a head, 6 with a tail; 0: chosen by the seed")
      ->capture_default_str()
      ->check(limbs_check());
  gen->add_option("--variation", fopt.variation, "Scale of the shapes' differences (0..2; 0: one surface)")
      ->capture_default_str()
      ->check(finite_in(0, 2));
  gen->add_option("--format", format, "Mesh format: obj, off or ply")
      ->check(CLI::IsMember({"obj", "off", "ply"}))
      ->capture_default_str();
  gen->add_option("-o,--output", outdir, "Output folder")->required();
  gen->add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  qs::tools::add_max_memory_option(*gen, max_memory);
  gen->get_option("--max-memory")->check(finite_in(0.001, 1e6));
  gen->add_flag("-q,--quiet", quiet, "Print nothing but errors");

  std::string input, output;
  std::optional<std::string> landmark_file;
  qs::family::RetessellateOptions ropt;
  auto* ret = app.add_subcommand("retessellate", "Re-tessellate a mesh, recording each new vertex's exact "
                                                 "(face, barycentric) origin on it");
  ret->add_option("MESH", input, "Closed genus-0 mesh")->required();
  ret->add_option("--landmarks", landmark_file, "Landmarks of MESH (default: found beside it) to transfer");
  ret->add_option("--faces", ropt.faces, "Target face count (about; 0: the input's)")
      ->capture_default_str()
      ->check(target_faces_check());
  ret->add_option("--iterations", ropt.iterations, "Rounds of isotropic remeshing (1..20)")
      ->capture_default_str()
      ->check(CLI::Range(1, 20));
  ret->add_flag("--keep-shape", ropt.keep_shape,
                "Keep the shape: remesh 3x finer, then simplify back to the face count (triangles crowd where the "
                "surface bends, so fingers and toes keep their shape; slower)");
  ret->add_option("-o,--output", output, "Output mesh (.obj .off .ply); OUT.map.json and OUT.landmarks.json beside it")
      ->required();
  qs::tools::add_max_memory_option(*ret, max_memory);
  ret->get_option("--max-memory")->check(finite_in(0.001, 1e6));
  ret->add_flag("-q,--quiet", quiet, "Print nothing but errors");

  PoseArgs pargs;
  auto* pose = app.add_subcommand("pose", "Pose a mesh: limbs found at its extremities bent or turned as rigidly as "
                                          "possible, the vertices and faces kept (an exact map)");
  pose->add_option("MESH", input, "Closed genus-0 mesh")->required();
  pose->add_option("--landmarks", landmark_file,
                   "Landmarks of MESH with 4 seeds (default: found beside it; none: chosen at the extremities)");
  pose->add_option("--pose", pargs.pose_name, "bend (every limb bent across), twist (turned about itself) or mixed")
      ->check(CLI::IsMember({"mixed", "bend", "twist"}))
      ->capture_default_str();
  pose->add_option("--seed", pargs.seed, "Seed: which limbs, axes, angles (the same seed gives the same files)")
      ->capture_default_str()
      ->check(seed_check());
  pose->add_option("--limbs", pargs.opt.limbs, "Limbs to pose (0: all found)")
      ->capture_default_str()
      ->check(CLI::Range(0, 64));
  pose->add_option("--min-angle", pargs.opt.min_angle_deg, "Smallest drawn angle, degrees (5..120)")
      ->capture_default_str()
      ->check(finite_in(5, 120));
  pose->add_option("--max-angle", pargs.opt.max_angle_deg, "Largest drawn angle, degrees (min..120)")
      ->capture_default_str()
      ->check(finite_in(5, 120));
  pose->add_flag("--retessellate", pargs.retessellate,
                 "Also re-tessellate the posed mesh as `retessellate` does: OUT_r.* with OUT_r.map.json onto OUT");
  pose->add_option("--faces", pargs.ropt.faces, "With --retessellate: target face count (0: the input's)")
      ->capture_default_str()
      ->check(target_faces_check());
  pose->add_option("--iterations", pargs.ropt.iterations, "With --retessellate: rounds of isotropic remeshing (1..20)")
      ->capture_default_str()
      ->check(CLI::Range(1, 20));
  pose->add_flag("--keep-shape", pargs.ropt.keep_shape, "With --retessellate: keep the shape (see retessellate)");
  pose->add_option("-o,--output", output,
                   "Output mesh (.obj .off .ply); OUT.landmarks.json, OUT.source.landmarks.json (the same for MESH) "
                   "and OUT.pose.json beside it")
      ->required();
  qs::tools::add_max_memory_option(*pose, max_memory);
  pose->get_option("--max-memory")->check(finite_in(0.001, 1e6));
  pose->add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (gen->parsed()) {
      fopt.seed = seed_value(seed_text);
      return run_generate(fopt, outdir, format, threads, max_memory, quiet);
    }
    if (pose->parsed()) {
      if (pargs.opt.min_angle_deg < pargs.opt.smallest_angle_deg) pargs.opt.smallest_angle_deg = pargs.opt.min_angle_deg;
      return run_pose(input, landmark_file, pargs, output, max_memory, quiet);
    }
    return run_retessellate(input, landmark_file, ropt, output, max_memory, quiet);
  });
}
