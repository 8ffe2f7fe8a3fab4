// DissectConfig <-> JSON (dissection.json's "options" object), its checks and its description.

#include <cmath>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <variant>

#include "qs/core/error.h"
#include "qs/core/json_strict.h"
#include "qs/pipeline/pipeline.h"

namespace qs::pipeline {

namespace {

using nlohmann::ordered_json;

template <class T>
using Ref = T& (*)(DissectConfig&);

// One option: its key, where it lives, its range (inclusive) and what it does.
struct Entry {
  const char* key;
  std::variant<Ref<bool>, Ref<int>, Ref<double>> ref;
  double lo, hi;
  const char* help;
};

constexpr double kInf = std::numeric_limits<double>::infinity();

// The schema, in the order of dissection.json. Descriptions are for --help-all.
const std::vector<Entry>& schema() {
  static const std::vector<Entry> entries = {
      {"tau", +[](DissectConfig& c) -> double& { return c.dissect.tau; }, 1, 1e6,
       "largest accepted patch L2 stretch (1 = isometric); a patch over it is split"},
      {"max_depth", +[](DissectConfig& c) -> int& { return c.dissect.max_depth; }, 0, 12, "deepest quinary split"},
      {"min_faces_to_split", +[](DissectConfig& c) -> int& { return c.dissect.min_faces_to_split; }, 10, 1 << 30,
       "smallest patch (in faces) that may be split"},
      {"w_bias", +[](DissectConfig& c) -> double& { return c.dissect.w_bias; }, -10, 10,
       "split rule: w = clamp(w_bias + log10(peak stretch), w_min, w_max)"},
      {"w_min", +[](DissectConfig& c) -> double& { return c.dissect.w_min; }, 0.05, 0.95, "split rule: smallest w"},
      {"w_max", +[](DissectConfig& c) -> double& { return c.dissect.w_max; }, 0.05, 0.95, "split rule: largest w"},
      {"peak_margin", +[](DissectConfig& c) -> double& { return c.dissect.peak_margin; }, 0, 0.49,
       "split rule: the stretch peak is clamped this far inside the square"},
      {"feature_cut_margin", +[](DissectConfig& c) -> double& { return c.dissect.feature_cut_margin; }, 0, 0.25,
       "features stay this far from a split's cuts (in the patch's square)"},
      {"feature_group_distance", +[](DissectConfig& c) -> double& { return c.dissect.feature_group_distance; }, 0,
       0.25, "features closer than this in a patch's square are aligned as one group"},
      {"geodesic_seed_curves", +[](DissectConfig& c) -> bool& { return c.dissect.geodesic_seed_curves; }, 0, 1,
       "seed curves straightened into geodesics (false: shortest edge paths)"},
      {"intrinsic_cotan", +[](DissectConfig& c) -> bool& { return c.dissect.intrinsic_cotan; }, 0, 1,
       "patch maps with cotangent weights on the intrinsic Delaunay triangulation (false: mean-value weights)"},
      {"fallback_maps", +[](DissectConfig& c) -> bool& { return c.dissect.fallback_maps; }, 0, 1,
       "when the result folds, dissect again with edge paths and mean-value weights and keep what folds less"},
      {"stretch_iterations", +[](DissectConfig& c) -> int& { return c.dissect.stretch_iterations; }, 0, 50,
       "rounds of stretch minimization of every final patch map (the patches do not change)"},
      {"max_patch_area", +[](DissectConfig& c) -> double& { return c.dissect.max_patch_area; }, 0, 1,
       "also split every patch larger than this fraction of its mesh's area (0: off)"},
      {"min_split_area", +[](DissectConfig& c) -> double& { return c.dissect.min_split_area; }, 0, 1,
       "do not split a bijective patch over tau smaller than this fraction of its mesh's area (0: off)"},
      {"force_split_area", +[](DissectConfig& c) -> double& { return c.dissect.force_split_area; }, 0, 1,
       "split a patch still over tau after repair that holds at least this fraction of its mesh's area (0: off)"},
      {"area_extra_depth", +[](DissectConfig& c) -> int& { return c.dissect.area_extra_depth; }, 0, 12,
       "levels past max_depth allowed to a large patch over tau (0: off)"},
      {"protrusion_stretch", +[](DissectConfig& c) -> double& { return c.dissect.protrusion_stretch; }, 0, 1e300,
       "split a patch stretched more than this with its stretch peak inside the centre child (0: off)"},
      {"same_pose", +[](DissectConfig& c) -> bool& { return c.dissect.same_pose; }, 0, 1,
       "the meshes are in one pose: splits placed by nearest points after the landmarks' similarity"},
      {"same_pose_detect", +[](DissectConfig& c) -> double& { return c.dissect.same_pose_detect; }, 0, 1,
       "treat the meshes as one pose when they lie within this fraction of the diagonal of each other (mean), 99% of them within twice that (0: never)"},
      {"register_poses", +[](DissectConfig& c) -> bool& { return c.dissect.register_poses; }, 0, 1,
       "in other poses of one surface, register the first mesh onto the others and dissect in one pose through that"},
      {"intrinsic_loops", +[](DissectConfig& c) -> bool& { return c.dissect.intrinsic_loops; }, 0, 1,
       "in other poses, route every mesh's seed loop along the first mesh's in geodesic coordinates of the landmarks"},
      {"same_pose_maps", +[](DissectConfig& c) -> bool& { return c.dissect.same_pose_maps; }, 0, 1,
       "in one pose, take every node map over from the first mesh's by nearest points"},
      {"refine_before_split", +[](DissectConfig& c) -> bool& { return c.refine_before_split; }, 0, 1,
       "refine every mesh's map of a node against the first mesh's before the node is split"},
      {"refine_maps", +[](DissectConfig& c) -> bool& { return c.refine_maps; }, 0, 1,
       "after the dissection, refine every mesh's chart toward a low-distortion map to the first mesh's"},
      {"refine_iterations", +[](DissectConfig& c) -> int& { return c.refine.iterations; }, 0, 1000,
       "map refinement: Newton steps per patch"},
      {"refine_across_borders", +[](DissectConfig& c) -> bool& { return c.refine.across_borders; }, 0, 1,
       "map refinement: move the patch curves of every mesh but the first too"},
      {"refine_border_sweeps", +[](DissectConfig& c) -> int& { return c.refine.border_sweeps; }, 0, 20,
       "map refinement: passes over the shared patch sides (through a registration at least 2 unless 0)"},
      {"refine_border_iterations", +[](DissectConfig& c) -> int& { return c.refine.border_iterations; }, 0, 1000,
       "map refinement: Newton steps per glued pair of patches"},
      {"refine_corners", +[](DissectConfig& c) -> bool& { return c.refine.move_corners; }, 0, 1,
       "map refinement: move the patch corners of every mesh but the first too (slower; better for different shapes)"},
      {"refine_corner_sweeps", +[](DissectConfig& c) -> int& { return c.refine.corner_sweeps; }, 0, 20,
       "map refinement: passes over the corners"},
      {"refine_corner_iterations", +[](DissectConfig& c) -> int& { return c.refine.corner_iterations; }, 0, 1000,
       "map refinement: Newton steps per corner star"},
      {"pose_pull", +[](DissectConfig& c) -> double& { return c.pose_pull; }, 0, 1e6,
       "in one pose: weight of the refinement's pull toward the first mesh's nearest points (0: off; 100 times "
       "this through a registration)"},
      {"pose_border_iterations", +[](DissectConfig& c) -> int& { return c.pose_border_iterations; }, 0, 1000,
       "in one pose: Newton steps per glued pair of patches (in place of refine_border_iterations; 4 times this "
       "through a registration)"},
  };
  return entries;
}

// The shortest decimal text that reads back as x.
std::string number(double x) {
  for (int digits = 6;; ++digits) {
    std::ostringstream s;
    s << std::setprecision(digits) << x;
    if (digits >= 17 || std::stod(s.str()) == x) return s.str();
  }
}

std::string range_text(const Entry& e) {
  if (std::holds_alternative<Ref<bool>>(e.ref)) return "true or false";
  const bool integer = std::holds_alternative<Ref<int>>(e.ref);
  std::string what = integer ? "an integer" : "a number";
  if (e.hi >= 1e300) return what + " >= " + number(e.lo);
  return what + " in [" + number(e.lo) + ", " + number(e.hi) + "]";
}

[[noreturn]] void bad_value(const std::string& name, const Entry& e, const std::string& found) {
  throw UsageError(name + ": \"" + e.key + "\" must be " + range_text(e) + ", found " + found);
}

}  // namespace

std::string config_to_json(const DissectConfig& config) {
  DissectConfig c = config;
  ordered_json o = ordered_json::object();
  for (const auto& e : schema()) {
    if (const auto* b = std::get_if<Ref<bool>>(&e.ref)) o[e.key] = (*b)(c);
    else if (const auto* i = std::get_if<Ref<int>>(&e.ref)) o[e.key] = (*i)(c);
    else o[e.key] = std::get<Ref<double>>(e.ref)(c);
  }
  return json_strict::dump(o, 2);
}

void validate_config(const DissectConfig& config) {
  DissectConfig c = config;
  for (const auto& e : schema()) {
    if (const auto* i = std::get_if<Ref<int>>(&e.ref)) {
      const int v = (*i)(c);
      if (v < e.lo || v > e.hi) bad_value("the configuration", e, std::to_string(v));
    } else if (const auto* d = std::get_if<Ref<double>>(&e.ref)) {
      const double v = (*d)(c);
      if (!(v >= e.lo && v <= e.hi)) bad_value("the configuration", e, number(v));
    }
  }
  if (c.dissect.w_min > c.dissect.w_max)
    throw UsageError("the configuration: \"w_min\" (" + number(c.dissect.w_min) + ") must not exceed \"w_max\" (" +
                     number(c.dissect.w_max) + ")");
}

DissectConfig config_from_json(const std::string& text, const std::string& name) {
  nlohmann::json doc;
  try {
    doc = json_strict::parse(text, name);
  } catch (const InvalidInput& e) {
    throw UsageError(e.what());
  }
  if (!doc.is_object()) throw UsageError(name + ": expected a JSON object (dissection.json or its \"options\")");
  // A whole dissection.json: its options.
  if (doc.contains("format")) {
    if (doc["format"] != "qs-dissection" || !doc.contains("options"))
      throw UsageError(name + ": not a qs-dissection file nor an options object (\"format\" is " +
                       json_strict::describe(doc["format"]) + ")");
    const nlohmann::json options = doc["options"];
    doc = options;
    if (!doc.is_object()) throw UsageError(name + ": \"options\" must be an object");
  }
  DissectConfig c;
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    const Entry* entry = nullptr;
    for (const auto& e : schema())
      if (it.key() == e.key) entry = &e;
    if (entry == nullptr)
      throw UsageError(name + ": unknown option \"" + json_strict::printable(it.key(), 80) +
                       "\" (qs-dissect --help-all lists the options)");
    const nlohmann::json& v = it.value();
    if (const auto* b = std::get_if<Ref<bool>>(&entry->ref)) {
      if (!v.is_boolean()) bad_value(name, *entry, json_strict::describe(v));
      (*b)(c) = v.get<bool>();
    } else if (const auto* i = std::get_if<Ref<int>>(&entry->ref)) {
      long long x = 0;
      if (!json_strict::integer_in(v, static_cast<long long>(entry->lo), static_cast<long long>(entry->hi), x))
        bad_value(name, *entry, json_strict::describe(v));
      (*i)(c) = static_cast<int>(x);
    } else {
      double x = 0;
      if (!json_strict::finite_number(v, x) || !(x >= entry->lo && x <= entry->hi))
        bad_value(name, *entry, json_strict::describe(v));
      std::get<Ref<double>>(entry->ref)(c) = x;
    }
  }
  validate_config(c);
  return c;
}

DissectConfig read_config(const std::filesystem::path& file) {
  return config_from_json(json_strict::read_text_file(file, "configuration (JSON)"),
                          json_strict::printable(file.string()));
}

std::string describe_config() {
  const DissectConfig defaults;
  DissectConfig c = defaults;
  std::ostringstream out;
  for (const auto& e : schema()) {
    std::string value;
    if (const auto* b = std::get_if<Ref<bool>>(&e.ref)) value = (*b)(c) ? "true" : "false";
    else if (const auto* i = std::get_if<Ref<int>>(&e.ref)) value = std::to_string((*i)(c));
    else value = number(std::get<Ref<double>>(e.ref)(c));
    out << "  " << std::left << std::setw(26) << e.key << " " << std::setw(7) << value << " " << e.help << " ("
        << range_text(e) << ")\n";
  }
  return out.str();
}

}  // namespace qs::pipeline
