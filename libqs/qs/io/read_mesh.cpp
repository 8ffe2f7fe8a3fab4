#include "qs/io/read_mesh.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "qs/core/error.h"
#include "qs/io/detail_parse.h"

namespace qs::io {

namespace {

std::string lower(std::string s) {
  for (char& c : s)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return s;
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

std::string read_whole_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw IoError(path.string() + ": cannot read: it is a directory");
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file)
    throw IoError(path.string() + ": cannot open for reading (" + std::strerror(errno) + ")");
  std::string data;
  char buffer[1 << 16];
  for (;;) {
    const std::size_t n = std::fread(buffer, 1, sizeof buffer, file.get());
    data.append(buffer, n);
    if (n < sizeof buffer) break;
  }
  if (std::ferror(file.get()))
    throw IoError(path.string() + ": read error (" + std::strerror(errno) + ")");
  return data;
}

}  // namespace

MeshFormat format_from_path(const std::filesystem::path& path) {
  const std::string ext = lower(path.extension().string());
  if (ext == ".obj") return MeshFormat::Obj;
  if (ext == ".off") return MeshFormat::Off;
  if (ext == ".ply") return MeshFormat::Ply;
  if (ext == ".stl") return MeshFormat::Stl;
  throw InvalidInput(path.string() + ": unknown mesh format" +
                     (ext.empty() ? std::string(" (no extension)")
                                  : " '" + path.extension().string() + "'") +
                     "; supported extensions are .obj .off .ply .stl");
}

const char* format_name(MeshFormat format) {
  switch (format) {
    case MeshFormat::Obj: return "OBJ";
    case MeshFormat::Off: return "OFF";
    case MeshFormat::Ply: return "PLY";
    case MeshFormat::Stl: return "STL";
  }
  return "unknown";
}

ReadResult read_mesh(const std::filesystem::path& path) {
  const MeshFormat format = format_from_path(path);
  const std::string data = read_whole_file(path);
  return read_mesh_from_memory(data, format, path.string());
}

ReadResult read_mesh_from_memory(std::string_view data, MeshFormat format, const std::string& name) {
  if (data.empty()) detail::fail(name, std::string("file is empty; expected a ") + format_name(format) + " mesh");
  if (detail::trim(data).empty())
    detail::fail(name, std::string("file contains only white space; expected a ") +
                           format_name(format) + " mesh");
  ReadResult result;
  switch (format) {
    case MeshFormat::Obj: result = detail::read_obj(data, name); break;
    case MeshFormat::Off: result = detail::read_off(data, name); break;
    case MeshFormat::Ply: result = detail::read_ply(data, name); break;
    case MeshFormat::Stl: result = detail::read_stl(data, name); break;
  }
  result.report.format = format;
  return result;
}

}  // namespace qs::io
