// qs-family: test data with exact ground truth.
//   qs-family generate  -> N smooth shapes with limbs, each with its own tessellation, landmarks
//                          and a map file to the common parameter sphere.
//   qs-family retessellate MESH -> a new tessellation of the same surface, with each vertex's
//                          exact origin on MESH (a "surface" map file) and transferred landmarks.
//
// Exit codes: 0 written; 1 usage; 2 invalid input (a rejected mesh, bad landmarks, an option out of
// range); 3 i/o; 4 the re-tessellation is not a usable mesh; 70 internal. Nothing is written
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
                 bool quiet) {
  qs::Context ctx;
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

int run_retessellate(const std::string& input, const std::optional<std::string>& landmark_file,
                     const qs::family::RetessellateOptions& opt, const std::string& output, bool quiet) {
  const qs::pipeline::Input in = qs::pipeline::load_input(input, landmark_file);
  if (in.valid.vertex_map.size() != in.read.mesh.positions.size() || in.valid.report.orientation_flipped ||
      in.valid.mesh.num_vertices() != in.read.mesh.num_vertices())
    throw qs::InvalidInput(input + ": the mesh has unreferenced vertices or faces inward; origins would not refer "
                           "to the file as written (clean it first, e.g. by writing what qs-inspect accepts)");
  const qs::family::Retessellation r = qs::family::retessellate(in.valid.mesh, opt);
  const fs::path out(output);
  if (out.has_parent_path()) make_dir(out.parent_path());
  const fs::path base = out.parent_path() / out.stem();
  qs::family::SurfaceMap map;
  map.domain = qs::family::MapDomain::Surface;
  std::error_code ec;
  const fs::path abs_in = fs::absolute(input), abs_dir = fs::absolute(out).parent_path();
  const fs::path rel = fs::relative(abs_in, abs_dir, ec);
  map.reference = ec || rel.empty() ? abs_in.string() : rel.string();
  map.reference_vertices = in.valid.mesh.num_vertices();
  map.reference_faces = in.valid.mesh.num_faces();
  map.origins = r.origins;
  // Landmarks: each point of the input goes to its closest point of the new tessellation.
  std::string landmarks_text;
  if (in.landmarks) {
    const qs::metro::SurfaceDistance target(r.mesh, "retessellation");
    auto ref = [&](const qs::landmarks::Landmark& l) {
      const qs::Vec3 p = qs::landmarks::position_of(in.valid.mesh, l.where);
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
    landmarks_text = "{\n";
    if (!in.landmarks->seeds.empty()) {
      landmarks_text += "  \"seeds\": [\n";
      for (std::size_t i = 0; i < in.landmarks->seeds.size(); ++i)
        landmarks_text += "    " + ref(in.landmarks->seeds[i]) + (i + 1 < in.landmarks->seeds.size() ? ",\n" : "\n");
      landmarks_text += "  ]" + std::string(in.landmarks->features.empty() ? "\n" : ",\n");
    }
    if (!in.landmarks->features.empty()) {
      landmarks_text += "  \"features\": {\n";
      for (std::size_t i = 0; i < in.landmarks->features.size(); ++i)
        landmarks_text += "    " + nlohmann::json(in.landmarks->features[i].name).dump() + ": " +
                          ref(in.landmarks->features[i]) + (i + 1 < in.landmarks->features.size() ? ",\n" : "\n");
      landmarks_text += "  }\n";
    }
    landmarks_text += "}\n";
  }
  qs::io::write_mesh(out, r.mesh);
  qs::family::write_surface_map(base.string() + ".map.json", map);
  if (!landmarks_text.empty()) qs::write_file_atomically(base.string() + ".landmarks.json", landmarks_text);
  if (!quiet) {
    // The new surface is the input's only at the vertices: its faces are chords, so fine detail
    // (fingers, say) loses area and shape. Said, since a map between the two is then not an
    // isometry, and the ground truth between the vertices is only as good as the chords.
    const double in_area = qs::surface_area(in.valid.mesh);
    char change[64];
    std::snprintf(change, sizeof change, "%+.2f%%", in_area > 0 ? 100 * (qs::surface_area(r.mesh) / in_area - 1) : 0.0);
    const qs::metro::MetroResult gap = qs::metro::metro(in.valid.mesh, r.mesh);
    char hausdorff[64];
    std::snprintf(hausdorff, sizeof hausdorff, "%.3f%%", gap.diagonal > 0 ? 100 * gap.max / gap.diagonal : 0.0);
    std::cout << output << ": " << r.mesh.num_vertices() << " vertices, " << r.mesh.num_faces() << " faces, area "
              << change << " against the input, surfaces at most " << hausdorff << " of the diagonal apart; origins on "
              << input << " in " << base.string() << ".map.json"
              << (landmarks_text.empty() ? "" : "; landmarks in " + base.string() + ".landmarks.json") << "\n";
  }
  return 0;
}

}  // namespace



int main(int argc, char** argv) {
  CLI::App app{"Test data with exact ground truth for the correspondence benchmark (README \"Correspondence\").\n"
               "Exit codes: 0 written, 1 usage, 2 invalid input, 3 i/o, 4 unusable re-tessellation.",
               "qs-family"};
  app.require_subcommand(1);
  qs::family::FamilyOptions fopt;
  std::string outdir, format = "obj";
  bool quiet = false;
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
  gen->add_flag("--quiet", quiet, "Print nothing on success");

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
  ret->add_flag("--quiet", quiet, "Print nothing on success");

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (gen->parsed()) return run_generate(fopt, outdir, format, quiet);
    return run_retessellate(input, landmark_file, ropt, output, quiet);
  });
}
