#include "qs/dfi/retime.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "qs/core/error.h"
#include "qs/metro/metro.h"

namespace qs::dfi {
namespace {

// Every `step`-th sample of g (values, when it has any, subsampled too).
Grid coarser(const Grid& g, int step) {
  Grid c;
  c.origin = g.origin;
  c.spacing = g.spacing * step;
  for (int a = 0; a < 3; ++a) c.dims[a] = (g.dims[a] - 1) / step + 1;
  if (!g.values.empty()) {
    c.values.resize(c.size());
    for (int k = 0; k < c.dims[2]; ++k)
      for (int j = 0; j < c.dims[1]; ++j)
        for (int i = 0; i < c.dims[0]; ++i) c.values[c.index(i, j, k)] = g.values[g.index(i * step, j * step, k * step)];
  }
  return c;
}

// One dense sample: the coarse frame. Its distance structure (several times the mesh's memory)
// is built only while a change is measured, so that many dense frames fit.
struct Sample {
  double t = 0;
  TriMesh mesh;
};

Sample make_sample(const PreparedMorph& coarse, double t, int threads) {
  Sample s;
  s.t = t;
  s.mesh = polygonize(blend_field(coarse, t, threads));
  return s;
}

using Surface = std::unique_ptr<metro::SurfaceDistance>;

Surface surface_of(const Sample& s) {
  return s.mesh.faces.empty() ? nullptr : std::make_unique<metro::SurfaceDistance>(s.mesh, "frame");
}

// Two-sided largest distance from the vertices of one frame to the surface of the other.
double change(const Sample& a, const Surface& sa, const Sample& b, const Surface& sb, double empty_change) {
  if (!sa || !sb) return sa || sb ? empty_change : 0.0;
  double d = 0;
  for (const Vec3& p : a.mesh.positions) d = std::max(d, sb->distance(p));
  for (const Vec3& p : b.mesh.positions) d = std::max(d, sa->distance(p));
  return d;
}

}  // namespace

std::vector<double> equalize_times(const std::vector<double>& dense, const std::vector<double>& change, int frames,
                                   double uniform_share) {
  if (frames < 2 || dense.size() < 2 || change.size() + 1 != dense.size() || !(uniform_share >= 0 && uniform_share <= 1))
    throw InvalidInput("equalize_times: expected frames >= 2, dense samples with one change per step, share in [0, 1]");
  double total = 0;
  for (double c : change) total += std::max(0.0, c);
  const double share = total > 0 ? uniform_share : 1.0;
  // Cumulative measure at each dense sample, from 0 to 1.
  std::vector<double> cum(dense.size(), 0.0);
  double run = 0;
  for (size_t i = 1; i < dense.size(); ++i) {
    run += total > 0 ? std::max(0.0, change[i - 1]) / total : 0.0;
    cum[i] = (1 - share) * run + share * dense[i];
  }
  cum.back() = 1.0;
  std::vector<double> times(frames);
  size_t j = 0;
  for (int f = 0; f < frames; ++f) {
    const double c = static_cast<double>(f) / (frames - 1);
    while (j + 2 < cum.size() && cum[j + 1] < c) ++j;
    const double span = cum[j + 1] - cum[j];
    const double u = span > 0 ? std::clamp((c - cum[j]) / span, 0.0, 1.0) : 0.0;
    times[f] = dense[j] + u * (dense[j + 1] - dense[j]);
  }
  times.front() = 0.0;
  times.back() = 1.0;
  for (int f = 1; f < frames; ++f) times[f] = std::max(times[f], times[f - 1]);
  return times;
}

Retiming even_frame_times(const PreparedMorph& morph, int frames, const RetimeOptions& o, int threads) {
  if (frames < 2 || o.samples_per_frame < 1 || o.coarsen < 1 || o.refine_passes < 0 ||
      !(o.uniform_share >= 0 && o.uniform_share <= 1))
    throw InvalidInput("retime options out of range: frames >= 2, samples_per_frame >= 1, coarsen >= 1, "
                       "refine_passes >= 0, uniform_share in [0, 1]");
  // The morph on a coarser grid: the same fields and warps, every coarsen-th sample.
  PreparedMorph coarse;
  const PreparedMorph* m = &morph;
  if (o.coarsen > 1) {
    coarse.warp = morph.warp;
    coarse.source_sdf = coarser(morph.source_sdf, o.coarsen);
    coarse.target_sdf = coarser(morph.target_sdf, o.coarsen);
    coarse.source_warp = morph.source_warp;
    coarse.target_warp = morph.target_warp;
    coarse.bones = morph.bones;
    coarse.volume = morph.volume;  // the same iso-level rule (max_iso_shift in cells)
    coarse.max_iso_shift = morph.max_iso_shift;
    coarse.topology_control = morph.topology_control;  // the frames as they will be written
    coarse.source_genus = morph.source_genus;
    coarse.target_genus = morph.target_genus;
    if (!morph.bones.empty()) coarse.bone_grid = coarser(morph.bone_grid, o.coarsen);
    m = &coarse;
  }
  const Grid& g = m->source_sdf;
  const double empty_change = g.spacing * std::max({g.dims[0], g.dims[1], g.dims[2]});
  const int steps = o.samples_per_frame * (frames - 1);
  std::vector<Sample> samples;
  std::vector<double> ch(steps);
  Surface previous;
  for (int i = 0; i <= steps; ++i) {
    samples.push_back(make_sample(*m, static_cast<double>(i) / steps, threads));
    Surface current = surface_of(samples[i]);
    if (i > 0) ch[i - 1] = change(samples[i - 1], previous, samples[i], current, empty_change);
    previous = std::move(current);
  }
  previous.reset();
  // Bisect the dense steps that change more than half an output step (a jump cannot be spread over
  // several output frames unless it is sampled finer); at most `steps` new samples per pass.
  for (int pass = 0; pass < o.refine_passes; ++pass) {
    double total = 0;
    for (double c : ch) total += c;
    const double limit = 0.5 * total / (frames - 1);
    std::vector<Sample> next;
    std::vector<double> next_ch;
    int added = 0;
    for (size_t i = 0; i + 1 < samples.size(); ++i) {
      const bool split = ch[i] > limit && added < steps && samples[i + 1].t - samples[i].t > 1e-6;
      Sample& a = samples[i];
      if (!split) {
        next.push_back(std::move(a));
        next_ch.push_back(ch[i]);
        continue;
      }
      Sample mid = make_sample(*m, 0.5 * (a.t + samples[i + 1].t), threads);
      const Surface sa = surface_of(a), sm = surface_of(mid), sb = surface_of(samples[i + 1]);
      const double c0 = change(a, sa, mid, sm, empty_change), c1 = change(mid, sm, samples[i + 1], sb, empty_change);
      next.push_back(std::move(a));
      next_ch.push_back(c0);
      next.push_back(std::move(mid));
      next_ch.push_back(c1);
      ++added;
    }
    next.push_back(std::move(samples.back()));
    samples.swap(next);
    ch.swap(next_ch);
    if (added == 0) break;
  }
  Retiming r;
  for (const Sample& s : samples) r.dense_times.push_back(s.t);
  r.dense_change = ch;
  r.times = equalize_times(r.dense_times, r.dense_change, frames, o.uniform_share);
  return r;
}

}  // namespace qs::dfi
