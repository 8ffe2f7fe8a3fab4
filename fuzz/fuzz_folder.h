#pragma once
// For the readers that take a folder (dissection.json + charts, remesh.json + meshes): a private
// temporary folder holding the fixture's other files; each input is written as the JSON file.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

inline std::filesystem::path fuzz_folder(const std::string& name, const std::string& fixture_files) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("qs-fuzz-" + name + "-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  for (const auto& e : fs::directory_iterator(fixture_files))
    fs::copy_file(e.path(), dir / e.path().filename(), fs::copy_options::overwrite_existing);
  return dir;
}

inline void fuzz_write(const std::filesystem::path& file, const std::uint8_t* data, std::size_t size) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}
