// qs-metro: Metro-style two-sided distance between two meshes (mean, RMS, max), in absolute
// units and as a percentage of the bounding-box diagonal of the first mesh (A).
//
// Exit codes: 0 measured; 1 usage; 2 a mesh that cannot be measured (unparsable, no faces,
// a face index out of range, a NaN or infinite coordinate, zero total area); 3 a file that
// cannot be read or written. Meshes that qs-inspect would reject for other reasons (open,
// non-manifold, several components, any genus) are measured anyway, with a note.

#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/output_folder.h"
#include "qs/io/read_mesh.h"
#include "qs/mesh/validate.h"
#include "qs/metro/metro.h"
#include "tool_main.h"

namespace {

struct Input {
  std::string file;
  qs::TriMesh mesh;
  std::vector<std::string> problems;  ///< kinds that make it no qs input, though measurable
};

/// Reads a mesh and rejects only what metro cannot measure; other problems become notes.
Input load(const std::string& file, const char* which) {
  Input in;
  in.file = file;
  in.mesh = qs::io::read_mesh(file).mesh;
  const qs::mesh::ValidationResult valid = qs::mesh::validate(in.mesh);
  std::string fatal;
  for (const auto& p : valid.report.problems) {
    if (p.severity != qs::mesh::Severity::Fatal) continue;
    if (p.kind == "empty" || p.kind == "invalid_vertex_index" || p.kind == "non_finite_coordinates")
      fatal += "\n  " + p.message;
    else
      in.problems.push_back(p.kind);
  }
  if (!fatal.empty())
    throw qs::InvalidInput(file + " (" + which + "): cannot measure distances on this mesh:" + fatal);
  return in;
}

std::string num(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string pct(double v, double diagonal) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4g%%", 100.0 * v / diagonal);
  return buf;
}

std::string describe(const Input& in) {
  return in.file + " (" + std::to_string(in.mesh.num_vertices()) + " vertices, " +
         std::to_string(in.mesh.num_faces()) + " faces)";
}

std::string text_report(const Input& a, const Input& b, const qs::metro::MetroResult& r) {
  std::ostringstream s;
  const double d = r.diagonal;
  s << "qs-metro: A = " << describe(a) << ", B = " << describe(b) << "\n";
  for (const auto* in : {&a, &b})
    if (!in->problems.empty()) {
      s << "note: " << (in == &a ? "A" : "B") << " is not a closed genus-0 mesh (";
      for (size_t i = 0; i < in->problems.size(); ++i) s << (i ? ", " : "") << in->problems[i];
      s << "); measured anyway\n";
    }
  s << "bounding box diagonal of A: " << num(d) << " (used for the percentages)\n";
  auto side = [&](const char* label, const qs::metro::OneSided& o) {
    s << label << ": mean " << num(o.mean) << " (" << pct(o.mean, d) << "), rms " << num(o.rms) << " ("
      << pct(o.rms, d) << "), max " << num(o.max) << " (" << pct(o.max, d) << ") (" << o.samples
      << " surface samples";
    if (o.vertex_samples > 0) s << " + " << o.vertex_samples << " vertices";
    s << ")\n";
  };
  side("A -> B", r.a_to_b);
  side("B -> A", r.b_to_a);
  s << "Hausdorff (two-sided): max " << num(r.max) << " (" << pct(r.max, d) << "), mean " << num(r.mean)
    << " (" << pct(r.mean, d) << "), rms " << num(r.rms) << " (" << pct(r.rms, d) << ")\n";
  return s.str();
}

nlohmann::json mesh_json(const Input& in, double area) {
  return {{"file", in.file},
          {"vertices", in.mesh.num_vertices()},
          {"faces", in.mesh.num_faces()},
          {"area", area},
          {"problems", in.problems}};
}

nlohmann::json side_json(const qs::metro::OneSided& o, double d) {
  return {{"mean", o.mean},
          {"rms", o.rms},
          {"max", o.max},
          {"mean_percent", 100 * o.mean / d},
          {"rms_percent", 100 * o.rms / d},
          {"max_percent", 100 * o.max / d},
          {"max_at", {o.max_at.x(), o.max_at.y(), o.max_at.z()}},
          {"samples", o.samples},
          {"vertex_samples", o.vertex_samples}};
}

nlohmann::json json_report(const Input& a, const Input& b, const qs::metro::MetroResult& r,
                           std::uint64_t seed) {
  const double d = r.diagonal;
  return {{"a", mesh_json(a, r.area_a)},
          {"b", mesh_json(b, r.area_b)},
          {"diagonal", d},
          {"diagonal_of", "A"},
          {"seed", seed},
          {"a_to_b", side_json(r.a_to_b, d)},
          {"b_to_a", side_json(r.b_to_a, d)},
          {"two_sided",
           {{"max", r.max},
            {"mean", r.mean},
            {"rms", r.rms},
            {"max_percent", 100 * r.max / d},
            {"mean_percent", 100 * r.mean / d},
            {"rms_percent", 100 * r.rms / d}}}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Metro-style two-sided distance between two meshes: mean, RMS and max (Hausdorff) of\n"
               "the distances from points sampled on each to the surface of the other, absolute and\n"
               "as % of the bounding-box diagonal of A.\n"
               "Exit codes: 0 measured, 1 usage, 2 a mesh that cannot be measured, 3 a file unreadable\n"
               "or unwritable.",
               "qs-metro"};
  std::string file_a, file_b;
  long samples = 0;
  std::uint64_t seed = 1;
  bool as_json = false, no_vertices = false;
  std::optional<std::string> output;
  app.add_option("A", file_a, "First mesh (.obj .off .ply .stl); its bounding-box diagonal is the "
                              "reference for the percentages")->required();
  app.add_option("B", file_b, "Second mesh")->required();
  app.add_option("--samples", samples,
                 "Surface samples per direction (default: max(100000, 2 x the larger face count))")
      ->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "Seed of the sampling (the same seed gives the same numbers)");
  app.add_flag("--no-vertices", no_vertices, "Do not measure at the vertices (surface samples only)");
  app.add_flag("--json", as_json, "Print a JSON object instead of text");
  app.add_option("-o,--output", output, "Write the report to this file instead of stdout");
  long max_samples = 100000000;
  app.add_option("--max-samples", max_samples,
                 "Refuse a --samples count above this up front (the run time grows linearly with it)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);

  return qs::tools::run_tool(app, argc, argv, [&] {
    if (samples > max_samples)
      throw qs::UsageError("--samples " + std::to_string(samples) + " is more than --max-samples " +
                           std::to_string(max_samples) + " (the time grows linearly with the count); raise "
                           "--max-samples to allow it");
    if (output) qs::check_not_an_input(*output, {file_a, file_b}, "-o");
    const Input a = load(file_a, "A");
    const Input b = load(file_b, "B");
    qs::metro::MetroOptions opt;
    opt.face_samples = samples;
    opt.seed = seed;
    opt.sample_vertices = !no_vertices;
    qs::metro::MetroResult r;
    try {
      r = qs::metro::metro(a.mesh, b.mesh, opt);
    } catch (const qs::InvalidInput& e) {  // the library names the meshes "A" and "B"
      throw qs::InvalidInput(std::string(e.what()) + " (A = " + a.file + ", B = " + b.file + ")");
    }
    const std::string report = as_json ? json_report(a, b, r, seed).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n" : text_report(a, b, r);
    if (output) qs::write_file_atomically(*output, report);
    else std::cout << report;
    return 0;
  });
}
