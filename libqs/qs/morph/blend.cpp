#include "qs/morph/blend.h"

#include <Eigen/Geometry>
#include <cmath>
#include <sstream>

#include "qs/core/error.h"

namespace qs::morph {

Align align_from_name(const std::string& name) {
  if (name == "none") return Align::None;
  if (name == "rigid") return Align::Rigid;
  if (name == "similarity") return Align::Similarity;
  throw InvalidInput("unknown alignment '" + name + "' (expected none, rigid or similarity)");
}

std::vector<Vec3> align_to(const std::vector<Vec3>& shape, const std::vector<Vec3>& base, Align how) {
  if (shape.size() != base.size() || shape.empty())
    throw InvalidInput("align_to: " + std::to_string(shape.size()) + " and " + std::to_string(base.size()) +
                       " vertices; alignment needs two non-empty shapes with one vertex numbering");
  if (how == Align::None) return shape;
  const Eigen::Matrix4d t = fit_similarity(shape, base, how == Align::Similarity);
  std::vector<Vec3> out(shape.size());
  for (size_t i = 0; i < shape.size(); ++i) out[i] = t.topLeftCorner<3, 3>() * shape[i] + t.topRightCorner<3, 1>();
  return out;
}

std::vector<PathFrame> path_frames(int num_shapes, const std::vector<int>& stops, int frames) {
  if (frames < 2) throw InvalidInput("a morph path needs at least 2 frames (got " + std::to_string(frames) + ")");
  if (stops.size() < 2)
    throw InvalidInput("a morph path needs at least 2 stops (got " + std::to_string(stops.size()) + ")");
  for (size_t k = 0; k < stops.size(); ++k)
    if (stops[k] < 0 || stops[k] >= num_shapes)
      throw InvalidInput("path stop " + std::to_string(k) + " is shape " + std::to_string(stops[k]) + ", not in [0, " +
                         std::to_string(num_shapes) + ")");
  const int legs = static_cast<int>(stops.size()) - 1;
  std::vector<PathFrame> out(frames);
  for (int f = 0; f < frames; ++f) {
    PathFrame& fr = out[f];
    // f * legs is an exact integer, so the first and last frames land exactly on 0 and legs.
    fr.s = static_cast<double>(f) * legs / (frames - 1);
    fr.leg = std::min(static_cast<int>(std::floor(fr.s)), legs - 1);
    fr.t = fr.s - fr.leg;
    fr.weights.assign(num_shapes, 0.0);
    fr.weights[stops[fr.leg]] += 1.0 - fr.t;
    fr.weights[stops[fr.leg + 1]] += fr.t;
  }
  return out;
}

void check_weights(const std::vector<double>& weights, int num_shapes) {
  if (static_cast<int>(weights.size()) != num_shapes)
    throw InvalidInput("blend weights: " + std::to_string(weights.size()) + " given, expected one per shape (" +
                       std::to_string(num_shapes) + ")");
  double sum = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    if (!std::isfinite(weights[i]) || weights[i] < 0) {
      std::ostringstream s;
      s << "blend weights: weight " << i + 1 << " is " << weights[i] << "; every weight must be >= 0 (no extrapolation)";
      throw InvalidInput(s.str());
    }
    sum += weights[i];
  }
  if (std::abs(sum - 1) > 1e-6) {
    std::ostringstream s;
    s.precision(17);
    s << "blend weights: they sum to " << sum << ", expected 1 (within 1e-6)";
    throw InvalidInput(s.str());
  }
}

std::vector<Vec3> blend(const std::vector<std::vector<Vec3>>& positions, const std::vector<double>& weights) {
  check_weights(weights, static_cast<int>(positions.size()));
  const size_t nv = positions.empty() ? 0 : positions[0].size();
  for (size_t i = 1; i < positions.size(); ++i)
    if (positions[i].size() != nv)
      throw InvalidInput("blend: shape " + std::to_string(i) + " has " + std::to_string(positions[i].size()) +
                         " vertices, shape 0 has " + std::to_string(nv));
  std::vector<Vec3> out(nv, Vec3::Zero());
  bool first = true;
  for (size_t i = 0; i < positions.size(); ++i) {
    const double w = weights[i];
    if (w == 0) continue;
    const auto& p = positions[i];
    if (first) {
      for (size_t v = 0; v < nv; ++v) out[v] = w * p[v];  // w == 1: an exact copy
      first = false;
    } else {
      for (size_t v = 0; v < nv; ++v) out[v] += w * p[v];
    }
  }
  return out;
}

int shape_index(const std::vector<std::string>& names, const std::string& name) {
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<int>(i);
  std::string known;
  for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
  throw InvalidInput("unknown shape '" + name + "'; the shapes are: " + known);
}

}  // namespace qs::morph
