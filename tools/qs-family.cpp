// qs-family: test data with exact ground truth.
//   qs-family generate  -> N smooth shapes with limbs, each with its own tessellation, landmarks
//                          and a map file to the common parameter sphere.
//   qs-family retessellate MESH -> a new tessellation of the same surface, with each vertex's
//                          exact origin on MESH (a "surface" map file) and transferred landmarks.
//   qs-family pose MESH -> MESH in another pose (limbs bent or turned as rigidly as possible), with
//                          the same vertices and faces (the map is vertex i <-> vertex i),
//                          landmarks for both, and optionally the posed mesh re-tessellated.
//
// Exit codes: 0 written; 1 usage; 2 invalid input (a rejected mesh, bad landmarks, an option out of
// range); 3 i/o; 4 the re-tessellation is not a usable mesh, or no limb can be posed; 70 internal. Nothing is written
// unless everything was made.

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "qs/pipeline/pipeline.h"
#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/family/family.h"
#include "qs/family/pose.h"
#include "qs/family/retessellate.h"
#include "qs/family/surface_map.h"
#include "qs/io/write_mesh.h"
#include "qs/metro/metro.h"
#include "tool_main.h"

namespace fs = std::filesystem;

namespace {

std::string num(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

void make_dir(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw qs::IoError(dir.string() + ": cannot create the output folder");
}

int run_generate(const qs::family::FamilyOptions& opt, const std::string& outdir, const std::string& format,
                 int threads, bool quiet) {
  qs::Context ctx;
  ctx.threads = threads;
  const qs::family::Family fam = qs::family::generate_family(opt, ctx);
  const fs::path dir(outdir);
  make_dir(dir);
  nlohmann::json shapes = nlohmann::json::array();
  for (const auto& s : fam.shapes) {
    const std::string mesh_file = s.name + "." + format;
    qs::io::write_mesh(dir / mesh_file, s.mesh);
    qs::write_file_atomically(dir / (s.name + ".landmarks.json"), qs::family::landmarks_json(s));
    qs::family::SurfaceMap map;
    map.domain = qs::family::MapDomain::Sphere;
    map.sphere = s.parameters;
    qs::family::write_surface_map(dir / (s.name + ".map.json"), map);
    shapes.push_back({{"name", s.name},
                      {"mesh", mesh_file},
                      {"landmarks", s.name + ".landmarks.json"},
                      {"map", s.name + ".map.json"},
                      {"vertices", s.mesh.num_vertices()},
                      {"faces", s.mesh.num_faces()}});
    if (!quiet)
      std::cout << (dir / mesh_file).string() << ": " << s.mesh.num_vertices() << " vertices, " << s.mesh.num_faces()
                << " faces, " << s.features.size() << " features\n";
  }
  nlohmann::json doc = {{"format", "qs-family"},
                        {"version", 1},
                        {"seed", opt.seed},
                        {"shapes", opt.shapes},
                        {"faces", opt.faces},
                        {"limbs", fam.limbs},
                        {"variation", opt.variation},
                        {"features", fam.limb_names},
                        {"meshes", shapes}};
  qs::write_file_atomically(dir / "family.json", doc.dump(2) + "\n");
  return 0;
}

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
  std::error_code ec;
  const fs::path abs_in = fs::absolute(ref_file), abs_dir = fs::absolute(fs::path(output)).parent_path();
  const fs::path rel = fs::relative(abs_in, abs_dir, ec);
  map.reference = ec || rel.empty() ? abs_in.string() : rel.string();
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

void write_retessellation(const RetessellationOut& o, const qs::TriMesh& ref, const std::string& ref_file,
                          const std::string& output, bool quiet) {
  const fs::path out(output);
  if (out.has_parent_path()) make_dir(out.parent_path());
  const fs::path base = out.parent_path() / out.stem();
  qs::io::write_mesh(out, o.r.mesh);
  qs::family::write_surface_map(base.string() + ".map.json", o.map);
  if (!o.landmarks_text.empty()) qs::write_file_atomically(base.string() + ".landmarks.json", o.landmarks_text);
  if (!quiet) {
    // The new surface is the input's only at the vertices: its faces are chords, so fine detail
    // (fingers, say) loses area and shape. Said, since a map between the two is then not an
    // isometry, and the ground truth between the vertices is only as good as the chords.
    const double in_area = qs::surface_area(ref);
    char change[64];
    std::snprintf(change, sizeof change, "%+.2f%%", in_area > 0 ? 100 * (qs::surface_area(o.r.mesh) / in_area - 1) : 0.0);
    const qs::metro::MetroResult gap = qs::metro::metro(ref, o.r.mesh);
    char hausdorff[64];
    std::snprintf(hausdorff, sizeof hausdorff, "%.3f%%", gap.diagonal > 0 ? 100 * gap.max / gap.diagonal : 0.0);
    std::cout << output << ": " << o.r.mesh.num_vertices() << " vertices, " << o.r.mesh.num_faces()
              << " faces, area " << change << " against the input, surfaces at most " << hausdorff
              << " of the diagonal apart; origins on " << ref_file << " in " << base.string() << ".map.json"
              << (o.landmarks_text.empty() ? "" : "; landmarks in " + base.string() + ".landmarks.json") << "\n";
  }
}

// Origins and landmarks refer to vertices and faces of the file as written: a mesh that
// validation changes (unreferenced vertices, faces turned) is refused.
void require_as_written(const qs::pipeline::Input& in, const std::string& input) {
  if (in.valid.vertex_map.size() != in.read.mesh.positions.size() || in.valid.report.orientation_flipped ||
      in.valid.mesh.num_vertices() != in.read.mesh.num_vertices())
    throw qs::InvalidInput(input + ": the mesh has unreferenced vertices or faces inward; origins would not refer "
                           "to the file as written (clean it first, e.g. by writing what qs-inspect accepts)");
}

int run_retessellate(const std::string& input, const std::optional<std::string>& landmark_file,
                     const qs::family::RetessellateOptions& opt, const std::string& output, bool quiet) {
  const qs::pipeline::Input in = qs::pipeline::load_input(input, landmark_file);
  require_as_written(in, input);
  const RetessellationOut o = make_retessellation(in.valid.mesh, in.landmarks, input, opt, output);
  write_retessellation(o, in.valid.mesh, input, output, quiet);
  return 0;
}

// A landmark as a reference of the mesh file: its vertex, else its face and weights.
std::string landmark_ref(const qs::landmarks::Landmark& l) {
  if (l.vertex >= 0) return std::to_string(l.vertex);
  return "{\"face\": " + std::to_string(l.where.face) + ", \"bary\": [" + num(l.where.bary[0]) + ", " +
         num(l.where.bary[1]) + ", " + num(l.where.bary[2]) + "]}";
}

struct PoseArgs {
  qs::family::PoseOptions opt;
  std::string pose_name = "mixed";
  bool retessellate = false;
  qs::family::RetessellateOptions ropt;
};

int run_pose(const std::string& input, const std::optional<std::string>& landmark_file, const PoseArgs& args,
             const std::string& output, bool quiet) {
  const qs::pipeline::Input in = qs::pipeline::load_input(input, landmark_file);
  require_as_written(in, input);
  qs::family::PoseOptions opt = args.opt;
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
  const fs::path out(output);
  const fs::path base = out.parent_path() / out.stem();
  const std::string retess_file = base.string() + "_r" + out.extension().string();
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
                              {"input", input},
                              {"seed", opt.seed},
                              {"pose", args.pose_name},
                              {"landmarks", origin},
                              {"limbs_found", pose.limbs_found},
                              {"limbs_dropped", pose.limbs_dropped},
                              {"input_self_intersections", pose.input_self_intersections},
                              {"limbs", limbs}};
  if (out.has_parent_path()) make_dir(out.parent_path());
  qs::io::write_mesh(out, pose.mesh);
  qs::write_file_atomically(base.string() + ".landmarks.json", lm_text);
  qs::write_file_atomically(base.string() + ".source.landmarks.json", lm_text);
  qs::write_file_atomically(base.string() + ".pose.json", doc.dump(2) + "\n");
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
              << ", " << base.string() << ".source.landmarks.json; the map is vertex i <-> vertex i\n";
  }
  if (retess) write_retessellation(*retess, pose.mesh, output, retess_file, quiet);
  return 0;
}

}  // namespace



int main(int argc, char** argv) {
  CLI::App app{"Test data with exact ground truth for the correspondence benchmark (docs/correspondence.md).\n"
               "Exit codes: 0 written, 1 usage, 2 invalid input, 3 i/o, 4 unusable re-tessellation or no limb posed.",
               "qs-family"};
  app.require_subcommand(1);
  qs::family::FamilyOptions fopt;
  std::string outdir, format = "obj";
  bool quiet = false;
  int threads = 0;
  auto* gen = app.add_subcommand("generate", "N smooth genus-0 shapes with limbs, own tessellations, landmarks "
                                             "and map files to a common parameter sphere");
  gen->add_option("-n,--shapes", fopt.shapes, "Number of shapes (1..256)")->capture_default_str();
  gen->add_option("--seed", fopt.seed, "Seed of the family (the same seed gives the same files)")->capture_default_str();
  gen->add_option("--faces", fopt.faces, "Faces per shape (even, 200..2000000)")->capture_default_str();
  gen->add_option("--limbs", fopt.limbs, "4 legs, 5 with a head, 6 with a tail; 0: chosen by the seed")
      ->capture_default_str();
  gen->add_option("--variation", fopt.variation, "Scale of the shapes' differences (0..2; 0: one surface)")
      ->capture_default_str();
  gen->add_option("--format", format, "Mesh format: obj, off or ply")
      ->check(CLI::IsMember({"obj", "off", "ply"}))
      ->capture_default_str();
  gen->add_option("-o,--output", outdir, "Output folder")->required();
  gen->add_option("--threads", threads, "Threads (0: all hardware threads; the output does not depend on it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4096));
  gen->add_flag("-q,--quiet", quiet, "Print nothing but errors");

  std::string input, output;
  std::optional<std::string> landmark_file;
  qs::family::RetessellateOptions ropt;
  auto* ret = app.add_subcommand("retessellate", "Re-tessellate a mesh, recording each new vertex's exact "
                                                 "(face, barycentric) origin on it");
  ret->add_option("MESH", input, "Closed genus-0 mesh")->required();
  ret->add_option("--landmarks", landmark_file, "Landmarks of MESH (default: found beside it) to transfer");
  ret->add_option("--faces", ropt.faces, "Target face count (about; 0: the input's)")->capture_default_str();
  ret->add_option("--iterations", ropt.iterations, "Rounds of isotropic remeshing (1..20)")->capture_default_str();
  ret->add_flag("--keep-shape", ropt.keep_shape,
                "Keep the shape: remesh 3x finer, then simplify back to the face count (triangles crowd where the "
                "surface bends, so fingers and toes keep their shape; slower)");
  ret->add_option("-o,--output", output, "Output mesh (.obj .off .ply); OUT.map.json and OUT.landmarks.json beside it")
      ->required();
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
  pose->add_option("--seed", pargs.opt.seed, "Seed: which limbs, axes, angles (the same seed gives the same files)")
      ->capture_default_str();
  pose->add_option("--limbs", pargs.opt.limbs, "Limbs to pose (0: all found)")->capture_default_str();
  pose->add_option("--min-angle", pargs.opt.min_angle_deg, "Smallest drawn angle, degrees (5..120)")->capture_default_str();
  pose->add_option("--max-angle", pargs.opt.max_angle_deg, "Largest drawn angle, degrees (min..120)")->capture_default_str();
  pose->add_flag("--retessellate", pargs.retessellate,
                 "Also re-tessellate the posed mesh as `retessellate` does: OUT_r.* with OUT_r.map.json onto OUT");
  pose->add_option("--faces", pargs.ropt.faces, "With --retessellate: target face count (0: the input's)")
      ->capture_default_str();
  pose->add_option("--iterations", pargs.ropt.iterations, "With --retessellate: rounds of isotropic remeshing (1..20)")
      ->capture_default_str();
  pose->add_flag("--keep-shape", pargs.ropt.keep_shape, "With --retessellate: keep the shape (see retessellate)");
  pose->add_option("-o,--output", output,
                   "Output mesh (.obj .off .ply); OUT.landmarks.json, OUT.source.landmarks.json (the same for MESH) "
                   "and OUT.pose.json beside it")
      ->required();
  pose->add_flag("-q,--quiet", quiet, "Print nothing but errors");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (gen->parsed()) return run_generate(fopt, outdir, format, threads, quiet);
    if (pose->parsed()) {
      if (pargs.opt.min_angle_deg < pargs.opt.smallest_angle_deg) pargs.opt.smallest_angle_deg = pargs.opt.min_angle_deg;
      return run_pose(input, landmark_file, pargs, output, quiet);
    }
    return run_retessellate(input, landmark_file, ropt, output, quiet);
  });
}
