#pragma once
// Writing many meshes that share one face list (the frames of a morph): the face part of the file
// is made once, and frames are written by several threads (the files do not depend on how many).
//   obj: the text qs::io::write_mesh writes (numbers read back bit-exact);
//   ply: binary little-endian PLY, float64 x y z and uchar/int32 vertex_indices (exact, and about
//        half the bytes of the text: frame writing is bound by bytes written).
// Both read back with qs::io::read_mesh.

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "qs/core/context.h"
#include "qs/core/mesh.h"
#include "qs/morph/blend.h"

namespace qs::morph {

enum class FrameFormat { Obj, Ply };

/// "obj" / "ply" -> FrameFormat. \throws UsageError naming the supported formats.
FrameFormat frame_format(const std::string& name);
const char* extension(FrameFormat format);  ///< "obj" / "ply"

class FrameWriter {
 public:
  /// \throws InvalidInput for a negative vertex index.
  FrameWriter(const std::vector<Tri>& faces, FrameFormat format);
  /// The file's bytes for one frame. \throws InvalidInput when positions are too few for the faces.
  std::string bytes(const std::vector<Vec3>& positions) const;
  /// Writes one frame atomically. \throws IoError, InvalidInput.
  void write(const std::filesystem::path& path, const std::vector<Vec3>& positions) const;

 private:
  FrameFormat format_;
  size_t num_faces_;
  long long max_index_ = -1;
  std::string face_bytes_;
};

/// Blends and writes frame f as folder/files[f] for every f (blend(shapes, frames[f].weights)),
/// on `threads` threads (<= 0: Context::threads). Reports progress ("frames", fraction),
/// checks the cancel flag. \throws what FrameWriter::write and blend throw (the lowest frame's).
void write_frames(const std::filesystem::path& folder, const std::vector<std::string>& files,
                  const std::vector<std::vector<Vec3>>& shapes, const std::vector<Tri>& faces,
                  const std::vector<PathFrame>& frames, FrameFormat format, int threads = 0,
                  const Context& context = {});

}  // namespace qs::morph
