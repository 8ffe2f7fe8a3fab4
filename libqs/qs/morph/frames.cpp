#include "qs/morph/frames.h"
#include "qs/morph/number_text_detail.h"

#include <algorithm>
#include <charconv>
#include <cstdint>
#include <cstring>

#include "qs/core/atomic_file.h"
#include "qs/core/error.h"
#include "qs/core/parallel.h"

namespace qs::morph {
namespace {

using detail::append_number;

bool little_endian() {
  const uint16_t one = 1;
  unsigned char b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

// Appends the little-endian bytes of a 4- or 8-byte value.
template <class T>
void append_le(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (!little_endian()) std::reverse(b, b + sizeof(T));
  out.append(b, sizeof(T));
}

}  // namespace

FrameFormat frame_format(const std::string& name) {
  if (name == "obj") return FrameFormat::Obj;
  if (name == "ply") return FrameFormat::Ply;
  throw UsageError("frame format '" + name + "' is not supported; use obj or ply");
}

const char* extension(FrameFormat format) { return format == FrameFormat::Obj ? "obj" : "ply"; }

FrameWriter::FrameWriter(const std::vector<Tri>& faces, FrameFormat format) : format_(format), num_faces_(faces.size()) {
  face_bytes_.reserve(faces.size() * (format == FrameFormat::Obj ? 24 : 13));
  for (size_t f = 0; f < faces.size(); ++f) {
    const Tri& t = faces[f];
    for (int v : t) {
      if (v < 0) throw InvalidInput("frame faces: face " + std::to_string(f) + " has a negative vertex index");
      max_index_ = std::max<long long>(max_index_, v);
    }
    if (format == FrameFormat::Obj) {
      face_bytes_ += "f ";
      for (int k = 0; k < 3; ++k) {
        append_number(face_bytes_, static_cast<long long>(t[k]) + 1);
        face_bytes_ += k < 2 ? ' ' : '\n';
      }
    } else {
      face_bytes_ += static_cast<char>(3);
      for (int k = 0; k < 3; ++k) append_le(face_bytes_, static_cast<int32_t>(t[k]));
    }
  }
}

std::string FrameWriter::bytes(const std::vector<Vec3>& positions) const {
  if (static_cast<long long>(positions.size()) <= max_index_)
    throw InvalidInput("frame: " + std::to_string(positions.size()) + " vertices, but the faces use vertex " +
                       std::to_string(max_index_));
  const std::string nv = std::to_string(positions.size()), nf = std::to_string(num_faces_);
  std::string out;
  if (format_ == FrameFormat::Obj) {
    const std::string header = "# qs: " + nv + " vertices, " + nf + " triangles\n";
    // Formatted straight into the buffer: "v " + 3 numbers of at most 24 characters + separators.
    out.resize(header.size() + positions.size() * 80 + face_bytes_.size());
    char* at = out.data();
    at = std::copy(header.begin(), header.end(), at);
    char* const end = out.data() + out.size();
    for (const Vec3& p : positions) {
      *at++ = 'v';
      for (int c = 0; c < 3; ++c) {
        *at++ = ' ';
        at = std::to_chars(at, end, p[c]).ptr;
      }
      *at++ = '\n';
    }
    at = std::copy(face_bytes_.begin(), face_bytes_.end(), at);
    out.resize(static_cast<size_t>(at - out.data()));
    return out;
  } else {
    out.reserve(positions.size() * 24 + face_bytes_.size() + 256);
    out += "ply\nformat binary_little_endian 1.0\ncomment written by qs\nelement vertex " + nv +
           "\nproperty double x\nproperty double y\nproperty double z\nelement face " + nf +
           "\nproperty list uchar int vertex_indices\nend_header\n";
    for (const Vec3& p : positions)
      for (int c = 0; c < 3; ++c) append_le(out, p[c]);
  }
  out += face_bytes_;
  return out;
}

void FrameWriter::write(const std::filesystem::path& path, const std::vector<Vec3>& positions) const {
  write_file_atomically(path, bytes(positions));
}

void write_frames(const std::filesystem::path& folder, const std::vector<std::string>& files,
                  const std::vector<std::vector<Vec3>>& shapes, const std::vector<Tri>& faces,
                  const std::vector<PathFrame>& frames, FrameFormat format, int threads, const Context& context) {
  if (files.size() != frames.size())
    throw InvalidInput("write_frames: " + std::to_string(files.size()) + " file names for " +
                       std::to_string(frames.size()) + " frames");
  const FrameWriter writer(faces, format);
  parallel_for(
      static_cast<int>(frames.size()), threads, context,
      [&](int f) { writer.write(folder / files[f], blend(shapes, frames[f].weights)); }, "frames");
}

}  // namespace qs::morph
