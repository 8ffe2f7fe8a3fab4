#include "qs/morph/frame_maps.h"
#include "qs/morph/number_text_detail.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/parallel.h"
#include "qs/image/image_file.h"
#include "qs/morph/frames.h"
#include "qs/morph/blend.h"

namespace fs = std::filesystem;

namespace qs::morph {
namespace {

using detail::append_number;

}  // namespace

NormalAtlases read_normal_atlases(const fs::path& bake_dir, const std::vector<std::string>& stems) {
  NormalAtlases out;
  for (const std::string& stem : stems) {
    const fs::path path = bake_dir / (stem + "_normal.png");
    if (!fs::exists(path)) throw IoError(path.string() + ": no such file (the normal map of shape '" + stem + "')");
    std::vector<unsigned char> bytes = image::read_file_bytes(path);
    std::string expected = "the 8-bit RGB normal map of shape '" + stem + "' written by qs-bake";
    if (!out.rgb.empty())
      expected += ", " + std::to_string(out.width) + " x " + std::to_string(out.height) + " as the other maps";
    image::RgbPixels px = image::decode_png(bytes, path.string(), {expected});
    if (out.rgb.empty()) {
      out.width = px.width;
      out.height = px.height;
    } else if (px.width != out.width || px.height != out.height) {
      throw InvalidInput(path.string() + ": " + std::to_string(px.width) + " x " + std::to_string(px.height) +
                         ", the other maps are " + std::to_string(out.width) + " x " + std::to_string(out.height) +
                         " (the maps must come from one qs-bake run)");
    }
    if (px.bits != 8) {
      px.u8.resize(static_cast<size_t>(px.width) * px.height * 3);
      for (size_t i = 0; i < px.u8.size(); ++i) px.u8[i] = px.to8(i);
    }
    out.rgb.push_back(std::move(px.u8));
    out.png.push_back(std::move(bytes));
  }
  return out;
}

std::vector<unsigned char> blend_normal_maps(const NormalAtlases& atlases, const std::vector<double>& weights) {
  check_weights(weights, static_cast<int>(atlases.rgb.size()));
  const size_t n = static_cast<size_t>(atlases.width) * atlases.height;
  for (size_t i = 0; i < weights.size(); ++i)  // one shape alone: its bytes
    if (weights[i] == 1.0) return atlases.rgb[i];
  double decode[256];
  for (int c = 0; c < 256; ++c) decode[c] = c / 127.5 - 1;
  std::vector<size_t> used;
  for (size_t i = 0; i < weights.size(); ++i)
    if (weights[i] != 0) used.push_back(i);
  std::vector<unsigned char> out(n * 3);
  for (size_t t = 0; t < n; ++t) {
    double s[3] = {0, 0, 0};
    for (size_t i : used) {
      const unsigned char* c = &atlases.rgb[i][3 * t];
      for (int k = 0; k < 3; ++k) s[k] += weights[i] * decode[c[k]];
    }
    const double len = std::sqrt(s[0] * s[0] + s[1] * s[1] + s[2] * s[2]);
    if (len > 1e-12) {
      for (int k = 0; k < 3; ++k) {
        const double e = std::clamp(s[k] / len * 0.5 + 0.5, 0.0, 1.0) * 255.0 + 0.5;  // round half up
        out[3 * t + k] = static_cast<unsigned char>(e);
      }
    } else {
      out[3 * t] = out[3 * t + 1] = 128;
      out[3 * t + 2] = 255;
    }
  }
  return out;
}

std::vector<unsigned char> encode_png_rgb8(int width, int height, const std::vector<unsigned char>& rgb) {
  if (width < 1 || height < 1 || rgb.size() != static_cast<size_t>(width) * height * 3)
    throw InvalidInput("encode_png_rgb8: " + std::to_string(rgb.size()) + " bytes for " + std::to_string(width) + " x " +
                       std::to_string(height) + " RGB texels");
  return image::encode_png(width, height, rgb, 3);  // zlib level 3: 2x faster than 6, 1.2x larger here
}

TexturedObjWriter::TexturedObjWriter(const std::vector<Tri>& faces, const BakedShape& baked) {
  if (baked.faces.size() != faces.size())
    throw InvalidInput("textured frames: the bake has " + std::to_string(baked.faces.size()) + " faces, the remesh " +
                       std::to_string(faces.size()));
  for (const Tri& t : faces)
    for (int v : t) num_vertices_ = std::max(num_vertices_, static_cast<size_t>(v) + 1);
  for (const Vec2& uv : baked.texcoords) {
    uv_and_faces_ += "vt ";
    append_number(uv_and_faces_, uv.x());
    uv_and_faces_ += ' ';
    append_number(uv_and_faces_, 1.0 - uv.y());  // glTF's v runs down, OBJ's up
    uv_and_faces_ += '\n';
  }
  for (size_t f = 0; f < faces.size(); ++f) {
    uv_and_faces_ += 'f';
    for (int k = 0; k < 3; ++k) {
      uv_and_faces_ += ' ';
      append_number(uv_and_faces_, faces[f][k] + 1);
      uv_and_faces_ += '/';
      append_number(uv_and_faces_, baked.faces[f][k] + 1);
    }
    uv_and_faces_ += '\n';
  }
}

std::string TexturedObjWriter::obj(const std::vector<Vec3>& positions, const std::string& mtl_file) const {
  if (positions.size() < num_vertices_)
    throw InvalidInput("textured frame: " + std::to_string(positions.size()) + " vertices, the faces need " +
                       std::to_string(num_vertices_));
  std::string out = "# qs-morph frame with a morphing normal map\nmtllib " + mtl_file + "\nusemtl frame\n";
  out.reserve(positions.size() * 64 + uv_and_faces_.size() + out.size());
  for (const Vec3& p : positions) {
    out += 'v';
    for (int c = 0; c < 3; ++c) {
      out += ' ';
      append_number(out, p[c]);
    }
    out += '\n';
  }
  out += uv_and_faces_;
  return out;
}

std::string TexturedObjWriter::mtl(const std::string& normal_png) {
  return "# qs-morph: tangent-space normal map (linear, OpenGL green)\nnewmtl frame\nKd 0.8 0.8 0.8\nKs 0 0 0\n"
         "map_Bump " + normal_png + "\nnorm " + normal_png + "\n";
}

void write_textured_frames(const fs::path& folder, const std::vector<std::string>& names,
                           const std::vector<std::vector<Vec3>>& shapes, const std::vector<Tri>& faces,
                           const BakedShape& baked, const NormalAtlases& atlases, const std::vector<PathFrame>& frames,
                           int threads, const Context& context) {
  if (names.size() != frames.size())
    throw InvalidInput("write_textured_frames: " + std::to_string(names.size()) + " names for " +
                       std::to_string(frames.size()) + " frames");
  if (atlases.rgb.size() != shapes.size())
    throw InvalidInput("write_textured_frames: " + std::to_string(atlases.rgb.size()) + " normal maps for " +
                       std::to_string(shapes.size()) + " shapes");
  const TexturedObjWriter writer(faces, baked);
  parallel_for(
      static_cast<int>(frames.size()), threads, context,
      [&](int f) {
        const std::vector<double>& w = frames[f].weights;
        int alone = -1;  // a frame that is one shape gets that shape's PNG as it is
        for (size_t i = 0; i < w.size(); ++i)
          if (w[i] == 1.0 && i < atlases.png.size()) alone = static_cast<int>(i);
        const std::vector<unsigned char> png =
            alone >= 0 ? atlases.png[alone] : encode_png_rgb8(atlases.width, atlases.height, blend_normal_maps(atlases, w));
        const std::string& name = names[f];
        {
          AtomicFile file(folder / (name + "_normal.png"));
          file.stream().write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
          file.commit();
        }
        write_file_atomically(folder / (name + ".mtl"), TexturedObjWriter::mtl(name + "_normal.png"));
        write_file_atomically(folder / (name + ".obj"), writer.obj(blend(shapes, w), name + ".mtl"));
      },
      "textured frames");
}

}  // namespace qs::morph
