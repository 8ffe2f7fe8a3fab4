#pragma once
// Map files: a mesh's exact correspondence to a common domain, so that two meshes mapped to the
// same domain correspond exactly (README "Correspondence"). `<stem>.map.json`:
//
//   {"format": "qs-map", "version": 1, "domain": "sphere", "vertices": V,
//    "sphere": [[x, y, z], ...]}                         one unit vector per vertex
//
//   {"format": "qs-map", "version": 1, "domain": "surface", "vertices": V,
//    "reference": "woman.obj", "reference_vertices": RV, "reference_faces": RF,
//    "origins": [[face, b0, b1, b2], ...]}               one point of the reference per vertex
//
// Vertex i is vertex i of the mesh file as written. "sphere": the vertex's point on a parameter
// sphere shared by a family (qs-family); a point with barycentric weights b on a face maps to
// normalize(sum b_k s_k). "surface": the vertex lies exactly at the point (face, barycentric
// weights) of the reference mesh (qs-family retessellate); `reference` is a path relative to the
// map file's folder (or absolute). Meshes with identical connectivity share the domain "their
// (face, bary)" without any file.

#include <filesystem>
#include <string>
#include <vector>

#include "qs/core/mesh.h"
#include "qs/landmarks/landmarks.h"

namespace qs::family {

enum class MapDomain { Sphere, Surface };

struct SurfaceMap {
  MapDomain domain = MapDomain::Sphere;
  std::vector<Vec3> sphere;                        ///< Sphere: #V unit vectors
  std::string reference;                           ///< Surface: the reference mesh, as written
  int reference_vertices = 0, reference_faces = 0; ///< Surface: its counts (checked on use)
  std::vector<landmarks::SurfacePoint> origins;    ///< Surface: #V points of the reference
  int num_vertices() const {
    return static_cast<int>(domain == MapDomain::Sphere ? sphere.size() : origins.size());
  }
};

/// The JSON text (numbers that read back exactly, deterministic).
std::string surface_map_to_json(const SurfaceMap& map);

/// Writes a map file atomically. \throws IoError.
void write_surface_map(const std::filesystem::path& path, const SurfaceMap& map);

/// Reads a map file. \throws IoError if it cannot be read; InvalidInput naming the file and the
/// field for a malformed one (wrong format or version, a count that disagrees, a vector that is
/// not unit length within 1e-6, a face id < 0, weights that are negative or do not sum to 1).
SurfaceMap read_surface_map(const std::filesystem::path& path);

/// The same from text; `name` is used in messages.
SurfaceMap parse_surface_map(const std::string& text, const std::string& name);

}  // namespace qs::family
