#include "qs/render/render.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <string>
#include <system_error>

#include "qs/core/error.h"
#include "qs/image/image_file.h"

namespace qs::render {
namespace {

constexpr int kMaxSide = 16384;
constexpr int kSubBits = 8;  // rasterizer vertices are snapped to 1/256 pixel
constexpr std::int64_t kSub = std::int64_t{1} << kSubBits;
constexpr double kAmbient = 0.22;
constexpr Rgb kGrey = {200, 200, 200};
constexpr Rgb kDark = {25, 25, 25};
constexpr Rgb kRed = {255, 0, 0};

struct Rect {
  int x0, y0, x1, y1;  // pixels [x0, x1) x [y0, y1)
};

// A vertex in fixed-point pixel coordinates (y down).
struct FixedPoint {
  std::int64_t x, y;
};

FixedPoint to_fixed(double x, double y) {
  // Far-away points (only possible in uv layouts) are clamped so that the int64 edge
  // functions cannot overflow; such triangles are clipped anyway.
  static constexpr double lim = double(1 << 20);
  auto f = [](double v) { return static_cast<std::int64_t>(std::llround(std::clamp(v, -lim, lim) * kSub)); };
  return {f(x), f(y)};
}

std::int64_t edge_fn(const FixedPoint& a, const FixedPoint& b, std::int64_t px, std::int64_t py) {
  return (b.x - a.x) * (py - a.y) - (b.y - a.y) * (px - a.x);
}

// Calls frag(x, y, l0, l1, l2) for every pixel whose centre lies in the triangle, with the
// barycentric coordinates of that centre. Exact integer edge functions and the top-left rule:
// a pixel centre on an edge shared by two triangles belongs to exactly one of them, so
// coverage counts are meaningful. Either orientation is accepted; degenerate triangles
// cover nothing. Returns false for those.
template <class Frag>
bool raster_triangle(FixedPoint p0, FixedPoint p1, FixedPoint p2, const Rect& clip, Frag&& frag) {
  std::int64_t area = edge_fn(p0, p1, p2.x, p2.y);
  if (area == 0) return false;
  bool swapped = false;
  if (area < 0) {
    std::swap(p1, p2);
    area = -area;
    swapped = true;
  }
  const auto lo = [](std::int64_t a, std::int64_t b, std::int64_t c) { return std::min({a, b, c}); };
  const auto hi = [](std::int64_t a, std::int64_t b, std::int64_t c) { return std::max({a, b, c}); };
  // Pixel i has its centre at (i + 1/2) * kSub.
  const auto first_px = [](std::int64_t v) { return static_cast<int>((v - kSub / 2 + kSub - 1) >> kSubBits); };
  const auto last_px = [](std::int64_t v) { return static_cast<int>((v - kSub / 2) >> kSubBits); };
  const int xa = std::max(clip.x0, first_px(lo(p0.x, p1.x, p2.x)));
  const int xb = std::min(clip.x1 - 1, last_px(hi(p0.x, p1.x, p2.x)));
  const int ya = std::max(clip.y0, first_px(lo(p0.y, p1.y, p2.y)));
  const int yb = std::min(clip.y1 - 1, last_px(hi(p0.y, p1.y, p2.y)));
  if (xa > xb || ya > yb) return true;

  // w_k is the edge function of the edge opposite vertex k; with area > 0 the inside is w >= 0
  // (y points down). Top-left rule: keep w == 0 only on top edges (dy == 0, dx > 0) and left
  // edges (dy < 0); the others are biased by -1.
  const FixedPoint* e[3][2] = {{&p1, &p2}, {&p2, &p0}, {&p0, &p1}};
  std::int64_t row[3], step_x[3], step_y[3];
  const std::int64_t cx = std::int64_t{xa} * kSub + kSub / 2, cy = std::int64_t{ya} * kSub + kSub / 2;
  for (int k = 0; k < 3; ++k) {
    const FixedPoint& a = *e[k][0];
    const FixedPoint& b = *e[k][1];
    const std::int64_t dx = b.x - a.x, dy = b.y - a.y;
    const bool top_left = (dy == 0 && dx > 0) || dy < 0;
    row[k] = edge_fn(a, b, cx, cy) - (top_left ? 0 : 1);
    step_x[k] = -dy * kSub;
    step_y[k] = dx * kSub;
  }
  const double inv = 1.0 / static_cast<double>(area);
  for (int y = ya; y <= yb; ++y) {
    std::int64_t w0 = row[0], w1 = row[1], w2 = row[2];
    for (int x = xa; x <= xb; ++x) {
      if ((w0 | w1 | w2) >= 0) {
        // Undo the top-left bias for the weights (it is at most 1 in 2^16 of a pixel).
        const double l0 = static_cast<double>(w0) * inv, l1 = static_cast<double>(w1) * inv;
        const double l2 = std::max(0.0, 1.0 - l0 - l1);
        if (swapped) frag(x, y, l0, l2, l1);
        else frag(x, y, l0, l1, l2);
      }
      w0 += step_x[0];
      w1 += step_x[1];
      w2 += step_x[2];
    }
    row[0] += step_y[0];
    row[1] += step_y[1];
    row[2] += step_y[2];
  }
  return true;
}

// Calls plot(x, y, t, fx, fy) at about one point per pixel along the segment (pixel (x, y)
// holds the point (fx, fy) at parameter t), within clip.
template <class Plot>
void walk_segment(double x0, double y0, double x1, double y1, const Rect& clip, Plot&& plot) {
  const double dx = x1 - x0, dy = y1 - y0;
  const double len = std::max(std::abs(dx), std::abs(dy));
  if (!(len < 4.0 * kMaxSide)) return;  // also rejects NaN
  const int n = std::max(1, static_cast<int>(std::ceil(len)));
  for (int i = 0; i <= n; ++i) {
    const double t = static_cast<double>(i) / n;
    const double fx = x0 + t * dx, fy = y0 + t * dy;
    const int x = static_cast<int>(std::floor(fx)), y = static_cast<int>(std::floor(fy));
    if (x < clip.x0 || y < clip.y0 || x >= clip.x1 || y >= clip.y1) continue;
    plot(x, y, t, fx, fy);
  }
}

Rgb mix(const Rgb& a, const Rgb& b, double t) {
  Rgb out;
  for (int c = 0; c < 3; ++c)
    out[c] = static_cast<std::uint8_t>(std::lround((1 - t) * a[c] + t * b[c]));
  return out;
}

Image blank(int width, int height, const Rgb& colour) {
  Image img;
  img.width = width;
  img.height = height;
  img.rgb.resize(size_t{3} * width * height);
  for (size_t i = 0; i < img.rgb.size(); i += 3) std::copy(colour.begin(), colour.end(), img.rgb.begin() + i);
  return img;
}

void put(Image& img, int x, int y, const Rgb& c) {
  std::copy(c.begin(), c.end(), img.rgb.begin() + 3 * (size_t{static_cast<size_t>(y)} * img.width + x));
}

void check_size(int width, int height, const char* what) {
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide)
    throw InvalidInput(std::string(what) + " " + std::to_string(width) + "x" + std::to_string(height) +
                       " is out of range; width and height must be 1.." + std::to_string(kMaxSide));
}

void check_image(const Image& img, const std::string& what) {
  if (img.width < 0 || img.height < 0 ||
      img.rgb.size() != size_t{3} * static_cast<size_t>(img.width) * static_cast<size_t>(img.height))
    throw InvalidInput(what + ": image data has " + std::to_string(img.rgb.size()) + " bytes for " +
                       std::to_string(img.width) + "x" + std::to_string(img.height) + " RGB pixels");
}

// An orthonormal camera frame: z towards the viewer, x to the right, y up.
struct Frame {
  Vec3 x, y, z;
};

Frame camera_frame(const Vec3& view_dir, const Vec3& up) {
  if (!view_dir.allFinite() || view_dir.norm() < 1e-12)
    throw InvalidInput("view direction (" + std::to_string(view_dir.x()) + ", " + std::to_string(view_dir.y()) +
                       ", " + std::to_string(view_dir.z()) + ") is zero or not finite; give a non-zero vector");
  Frame f;
  f.z = view_dir.normalized();
  Vec3 u = up.allFinite() ? up : Vec3(0, 1, 0);
  Vec3 x = u.cross(f.z);
  if (x.norm() < 1e-6 * std::max(1.0, u.norm())) {
    // up is parallel to the view: take the axis least aligned with it.
    const Vec3 a = f.z.cwiseAbs();
    const int i = a.x() <= a.y() && a.x() <= a.z() ? 0 : (a.y() <= a.z() ? 1 : 2);
    Vec3 alt = Vec3::Zero();
    alt[i] = 1;
    x = alt.cross(f.z);
  }
  f.x = x.normalized();
  f.y = f.z.cross(f.x);
  return f;
}

// The used positions moved and scaled uniformly into [-1/2, 1/2]^3 around their bounding box's
// centre: the same picture (the view fits the box), but every difference, cross product and
// depth stays finite for any finite input, up to the largest double. Halves are taken before
// subtracting so that nothing overflows on the way.
std::vector<Vec3> normalized_positions(const std::vector<Vec3>& positions, const std::vector<char>& used) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (size_t v = 0; v < positions.size(); ++v)
    if (used[v]) lo = lo.cwiseMin(positions[v]), hi = hi.cwiseMax(positions[v]);
  std::vector<Vec3> out(positions.size(), Vec3::Zero());
  if (!(lo.x() <= hi.x())) return out;  // no used vertex
  const Vec3 centre = 0.5 * lo + 0.5 * hi;
  const double half = (0.5 * hi - 0.5 * lo).maxCoeff();  // finite: at most the largest double
  if (!(half > 0)) return out;                             // a single point
  for (size_t v = 0; v < positions.size(); ++v)
    if (used[v]) out[v] = (0.5 * positions[v] - 0.5 * centre) / half;
  return out;
}

}  // namespace

Image render_mesh(const TriMesh& mesh, const std::vector<Rgb>* face_colours, const RenderOptions& options,
                  const std::vector<std::array<int, 2>>* highlight_edges) {
  check_size(options.width, options.height, "image size");
  const Frame cam = camera_frame(options.view_dir, options.up);
  const int W = options.width, H = options.height;
  const int nv = mesh.num_vertices(), nf = mesh.num_faces();
  if (face_colours && static_cast<int>(face_colours->size()) != nf)
    throw InvalidInput("face colours: " + std::to_string(face_colours->size()) + " colours for " +
                       std::to_string(nf) + " faces; give one per face");
  std::vector<char> used(nv, 0);
  for (int f = 0; f < nf; ++f)
    for (int v : mesh.faces[f]) {
      if (v < 0 || v >= nv)
        throw InvalidInput("face " + std::to_string(f) + " has vertex id " + std::to_string(v) +
                           " outside [0, " + std::to_string(nv) + ")");
      used[v] = 1;
    }
  if (highlight_edges)
    for (size_t i = 0; i < highlight_edges->size(); ++i)
      for (int v : (*highlight_edges)[i])
        if (v < 0 || v >= nv)
          throw InvalidInput("highlight edge " + std::to_string(i) + " has vertex id " + std::to_string(v) +
                             " outside [0, " + std::to_string(nv) + ")");
  for (int v = 0; v < nv; ++v)
    if (used[v] && !mesh.positions[v].allFinite())
      throw InvalidInput("vertex " + std::to_string(v) + " has a position that is not finite");
  const std::vector<Vec3> pos = normalized_positions(mesh.positions, used);

  // Project; fit the used vertices' screen box into the image with a margin.
  std::vector<Vec3> s(nv);  // screen x, y (pixels, y down), depth (larger is nearer)
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
  double z_lo = x_lo, z_hi = -x_lo;
  for (int v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    const Vec3& p = pos[v];
    s[v] = Vec3(p.dot(cam.x), p.dot(cam.y), p.dot(cam.z));
    x_lo = std::min(x_lo, s[v].x());
    x_hi = std::max(x_hi, s[v].x());
    y_lo = std::min(y_lo, s[v].y());
    y_hi = std::max(y_hi, s[v].y());
    z_lo = std::min(z_lo, s[v].z());
    z_hi = std::max(z_hi, s[v].z());
  }
  Image img = blank(W, H, options.background);
  if (nf == 0) return img;
  const double margin = 0.05 * std::min(W, H);
  const double inf = std::numeric_limits<double>::infinity();
  const double sx = x_hi > x_lo ? (W - 2 * margin) / (x_hi - x_lo) : inf;
  const double sy = y_hi > y_lo ? (H - 2 * margin) / (y_hi - y_lo) : inf;
  const double scale = std::isfinite(std::min(sx, sy)) ? std::min(sx, sy) : 1.0;  // 1: a single point
  const double cx = 0.5 * (x_lo + x_hi), cy = 0.5 * (y_lo + y_hi);
  for (int v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    s[v].x() = 0.5 * W + (s[v].x() - cx) * scale;
    s[v].y() = 0.5 * H - (s[v].y() - cy) * scale;
  }

  // Normals: flat per face, or area-weighted per vertex.
  std::vector<Vec3> face_n(nf);
  for (int f = 0; f < nf; ++f) {
    const auto& t = mesh.faces[f];
    face_n[f] = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
  }
  std::vector<Vec3> vert_n;
  if (options.smooth) {
    vert_n.assign(nv, Vec3::Zero());
    for (int f = 0; f < nf; ++f)
      for (int v : mesh.faces[f]) vert_n[v] += face_n[f];  // |cross| = 2 * area
    for (Vec3& n : vert_n) {
      const double len = n.norm();
      n = len > 0 ? Vec3(n / len) : Vec3::Zero();
    }
  }
  for (Vec3& n : face_n) {
    const double len = n.norm();
    n = len > 0 ? Vec3(n / len) : Vec3::Zero();
  }

  // Fill: z-buffer, face id and shade per pixel (shading resolved at the end).
  const size_t npx = size_t{static_cast<size_t>(W)} * H;
  std::vector<float> zbuf(npx, -std::numeric_limits<float>::infinity());
  std::vector<int> fid(npx, -1);
  std::vector<float> shade(npx, 0.f);
  const Rect full{0, 0, W, H};
  const Vec3& light = cam.z;  // head light
  for (int f = 0; f < nf; ++f) {
    const auto& t = mesh.faces[f];
    const Vec3 &a = s[t[0]], &b = s[t[1]], &c = s[t[2]];
    const double flat = kAmbient + (1 - kAmbient) * std::abs(face_n[f].dot(light));
    raster_triangle(to_fixed(a.x(), a.y()), to_fixed(b.x(), b.y()), to_fixed(c.x(), c.y()), full,
                    [&](int x, int y, double l0, double l1, double l2) {
                      const size_t i = size_t{static_cast<size_t>(y)} * W + x;
                      const float z = static_cast<float>(l0 * a.z() + l1 * b.z() + l2 * c.z());
                      if (!(z > zbuf[i])) return;
                      zbuf[i] = z;
                      fid[i] = f;
                      if (options.smooth) {
                        const Vec3 n = l0 * vert_n[t[0]] + l1 * vert_n[t[1]] + l2 * vert_n[t[2]];
                        const double len = n.norm();
                        shade[i] = static_cast<float>(
                            len > 0 ? kAmbient + (1 - kAmbient) * std::abs(n.dot(light)) / len : flat);
                      } else {
                        shade[i] = static_cast<float>(flat);
                      }
                    });
  }

  // Edges: depth-tested against the filled surface. A pixel shows an edge if the surface there
  // belongs to a face touching the edge, or lies no more than `bias` in front of it (about two
  // pixels of depth: enough for surfaces up to ~60 degrees from the screen, far less than the
  // distance to the back of a shape).
  const double world_per_px = 1.0 / scale;
  const double bias = 2.0 * world_per_px + 1e-9 * std::max(1.0, std::abs(z_hi) + std::abs(z_lo));
  const auto touches = [&](int face, int a, int b) {
    const auto& t = mesh.faces[face];
    return t[0] == a || t[1] == a || t[2] == a || t[0] == b || t[1] == b || t[2] == b;
  };
  std::vector<std::uint8_t> line(npx, 0);  // 1 wireframe, 2 highlight
  const auto draw_edge = [&](int a, int b, bool thick) {
    const Vec3 &pa = s[a], &pb = s[b];
    const double radius = thick ? 0.5 * std::max(2.0, std::min(W, H) / 300.0) : 0.0;
    const int r = static_cast<int>(std::ceil(radius));
    walk_segment(pa.x(), pa.y(), pb.x(), pb.y(), full, [&](int x, int y, double t, double fx, double fy) {
      const double z = pa.z() + t * (pb.z() - pa.z());
      const size_t i = size_t{static_cast<size_t>(y)} * W + x;
      if (fid[i] >= 0 && !touches(fid[i], a, b) && z + bias < zbuf[i]) return;
      if (!thick) {
        line[i] = std::max<std::uint8_t>(line[i], 1);
        return;
      }
      for (int yy = std::max(0, y - r); yy <= std::min(H - 1, y + r); ++yy)
        for (int xx = std::max(0, x - r); xx <= std::min(W - 1, x + r); ++xx) {
          const double ddx = xx + 0.5 - fx, ddy = yy + 0.5 - fy;
          if (ddx * ddx + ddy * ddy > radius * radius) continue;
          const size_t j = size_t{static_cast<size_t>(yy)} * W + xx;
          if (fid[j] >= 0 && !touches(fid[j], a, b) && z + bias * (1 + radius) < zbuf[j]) continue;
          line[j] = 2;
        }
    });
  };
  if (options.wireframe)
    for (int f = 0; f < nf; ++f)
      for (int k = 0; k < 3; ++k) draw_edge(mesh.faces[f][k], mesh.faces[f][(k + 1) % 3], false);
  if (highlight_edges)
    for (const auto& e : *highlight_edges) draw_edge(e[0], e[1], true);

  // Resolve.
  for (size_t i = 0; i < npx; ++i) {
    Rgb c = options.background;
    if (fid[i] >= 0) {
      const Rgb& base = face_colours ? (*face_colours)[fid[i]] : kGrey;
      for (int k = 0; k < 3; ++k)
        c[k] = static_cast<std::uint8_t>(std::clamp(std::lround(base[k] * shade[i]), 0L, 255L));
    }
    if (line[i] == 1) c = mix(c, kDark, 0.6);
    else if (line[i] == 2) c = kDark;
    std::copy(c.begin(), c.end(), img.rgb.begin() + 3 * i);
  }
  return img;
}

Image render_uv_layout(const std::vector<std::array<Vec2, 3>>& face_uv, const std::vector<int>& face_patch,
                       int patches, int tile_px, const std::vector<Rgb>& patch_colours) {
  if (face_uv.size() != face_patch.size())
    throw InvalidInput("uv layout: " + std::to_string(face_uv.size()) + " faces with uvs but " +
                       std::to_string(face_patch.size()) + " patch labels; give one of each per face");
  if (patches < 1) throw InvalidInput("uv layout: " + std::to_string(patches) + " patches; need at least 1");
  if (static_cast<int>(patch_colours.size()) != patches)
    throw InvalidInput("uv layout: " + std::to_string(patch_colours.size()) + " colours for " +
                       std::to_string(patches) + " patches; give one per patch");
  if (tile_px < 8 || tile_px > 4096)
    throw InvalidInput("uv layout: tile size " + std::to_string(tile_px) + " pixels is out of range 8..4096");
  int cols = 1;
  while (cols * cols < patches) ++cols;
  const int rows = (patches + cols - 1) / cols;
  if (std::int64_t{cols} * tile_px > kMaxSide || std::int64_t{rows} * tile_px > kMaxSide)
    throw InvalidInput("uv layout: " + std::to_string(patches) + " patches in tiles of " + std::to_string(tile_px) +
                       " pixels make an atlas wider or taller than " + std::to_string(kMaxSide) +
                       " pixels; use smaller tiles");
  const int nf = static_cast<int>(face_uv.size());
  for (int f = 0; f < nf; ++f) {
    if (face_patch[f] < 0 || face_patch[f] >= patches)
      throw InvalidInput("uv layout: face " + std::to_string(f) + " has patch " + std::to_string(face_patch[f]) +
                         " outside [0, " + std::to_string(patches) + ")");
    for (const Vec2& uv : face_uv[f])
      if (!uv.allFinite()) throw InvalidInput("uv layout: face " + std::to_string(f) + " has a uv that is not finite");
  }

  const int W = cols * tile_px, H = rows * tile_px;
  Image img = blank(W, H, {255, 255, 255});
  const int gap = std::max(2, tile_px / 16);
  const double side = tile_px - 2 * gap;
  const auto tile_rect = [&](int p) {
    const int tx = (p % cols) * tile_px, ty = (p / cols) * tile_px;
    return Rect{tx, ty, tx + tile_px, ty + tile_px};
  };
  const auto to_px = [&](int p, const Vec2& uv) {
    const Rect r = tile_rect(p);
    return Vec2(r.x0 + gap + uv.x() * side, r.y0 + gap + (1 - uv.y()) * side);
  };
  // Each tile: the unit square, very light, inside a light frame.
  for (int p = 0; p < patches; ++p) {
    const Rect r = tile_rect(p);
    for (int y = r.y0 + gap; y < r.y1 - gap; ++y)
      for (int x = r.x0 + gap; x < r.x1 - gap; ++x) put(img, x, y, {244, 244, 244});
    for (int k = 0; k < tile_px - 2 * gap + 2; ++k) {
      const int a = r.x0 + gap - 1 + k, b = r.y0 + gap - 1 + k;
      put(img, a, r.y0 + gap - 1, {190, 190, 190});
      put(img, a, r.y1 - gap, {190, 190, 190});
      put(img, r.x0 + gap - 1, b, {190, 190, 190});
      put(img, r.x1 - gap, b, {190, 190, 190});
    }
  }
  // Fill, counting coverage (exact: shared edges are covered once).
  const size_t npx = size_t{static_cast<size_t>(W)} * H;
  std::vector<std::uint8_t> cover(npx, 0), bad(npx, 0), outline(npx, 0);
  for (int f = 0; f < nf; ++f) {
    const int p = face_patch[f];
    const auto& uv = face_uv[f];
    const double signed_area = (uv[1] - uv[0]).x() * (uv[2] - uv[0]).y() - (uv[1] - uv[0]).y() * (uv[2] - uv[0]).x();
    const Vec2 a = to_px(p, uv[0]), b = to_px(p, uv[1]), c = to_px(p, uv[2]);
    raster_triangle(to_fixed(a.x(), a.y()), to_fixed(b.x(), b.y()), to_fixed(c.x(), c.y()), tile_rect(p),
                    [&](int x, int y, double, double, double) {
                      const size_t i = size_t{static_cast<size_t>(y)} * W + x;
                      if (cover[i] < 255) ++cover[i];
                      if (signed_area < 0) bad[i] = 1;
                      put(img, x, y, patch_colours[p]);
                    });
  }
  // Outlines, except in tiles under 48 pixels and for triangles under 4 pixels across: there
  // they would paint the whole patch dark.
  for (int f = 0; f < nf && side >= 48; ++f) {
    const int p = face_patch[f];
    const Vec2 a = to_px(p, face_uv[f][0]), b = to_px(p, face_uv[f][1]), c = to_px(p, face_uv[f][2]);
    const Vec2 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
    if ((hi - lo).maxCoeff() < 4.0) continue;
    for (int k = 0; k < 3; ++k) {
      const Vec2 a = to_px(p, face_uv[f][k]), b = to_px(p, face_uv[f][(k + 1) % 3]);
      walk_segment(a.x(), a.y(), b.x(), b.y(), tile_rect(p), [&](int x, int y, double, double, double) {
        outline[size_t{static_cast<size_t>(y)} * W + x] = 1;
      });
    }
  }
  for (size_t i = 0; i < npx; ++i) {
    if (!outline[i] && !bad[i] && cover[i] < 2) continue;
    Rgb c = {img.rgb[3 * i], img.rgb[3 * i + 1], img.rgb[3 * i + 2]};
    if (bad[i] || cover[i] >= 2) c = kRed;
    else c = mix(c, kDark, 0.55);
    std::copy(c.begin(), c.end(), img.rgb.begin() + 3 * i);
  }
  return img;
}

Image side_by_side(const std::vector<Image>& images) {
  int W = 0, H = 0;
  for (size_t k = 0; k < images.size(); ++k) {
    check_image(images[k], "side_by_side: image " + std::to_string(k));
    if (std::int64_t{W} + images[k].width > kMaxSide)
      throw InvalidInput("side_by_side: the images together are wider than " + std::to_string(kMaxSide) + " pixels");
    W += images[k].width;
    H = std::max(H, images[k].height);
  }
  Image out = blank(W, H, {255, 255, 255});
  int x0 = 0;
  for (const Image& im : images) {
    const int y0 = (H - im.height) / 2;
    for (int y = 0; y < im.height; ++y)
      std::copy_n(im.rgb.begin() + size_t{3} * y * im.width, size_t{3} * im.width,
                  out.rgb.begin() + 3 * (size_t{static_cast<size_t>(y0 + y)} * W + x0));
    x0 += im.width;
  }
  return out;
}

void write_png(const std::filesystem::path& path, const Image& image) {
  check_image(image, path.string());
  if (image.width < 1 || image.height < 1)
    throw InvalidInput(path.string() + ": cannot write an empty " + std::to_string(image.width) + "x" +
                       std::to_string(image.height) + " image");
  std::filesystem::path tmp = path;
  tmp += ".tmp-" + std::to_string(::getpid()) + ".png";
  const auto fail = [&](const std::string& why) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw IoError(path.string() + ": cannot write the PNG (" + why + ")");
  };
  const std::vector<unsigned char> bytes = qs::image::encode_png(image.width, image.height, image.rgb);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) fail("cannot create " + tmp.string());
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) fail("write failed (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) fail("cannot move the finished file into place: " + ec.message());
}

}  // namespace qs::render
