#pragma once
// Meshes made in code, for tests, examples and benchmarks. All closed ones are outward-oriented
// (positive signed volume), manifold and genus 0 unless named otherwise. Everything is
// deterministic: no randomness, the same arguments always give the same mesh.
// Invalid arguments (negative counts, sizes <= 0, too many faces) throw qs::InvalidInput.

#include <functional>
#include <vector>

#include "qs/core/mesh.h"

namespace qs::shapes {

/// Unit icosphere: a regular icosahedron whose faces are split in four `subdivisions` times
/// (edge midpoints projected to the sphere): 20 * 4^s faces, 10 * 4^s + 2 vertices.
/// \pre 0 <= subdivisions <= 9.
TriMesh icosphere(int subdivisions);

/// icosphere(subdivisions) scaled to semi-axes (a, b, c) along x, y, z. \pre a, b, c > 0.
TriMesh ellipsoid(double a, double b, double c, int subdivisions);

/// icosphere(subdivisions) with each vertex direction d moved to radius(d) * d.
/// Star-shaped about the origin, so never self-intersecting and still outward-oriented.
/// \pre radius(d) > 0 and finite for every unit d (checked at each vertex).
TriMesh displaced_sphere(const std::function<double(const Vec3&)>& radius, int subdivisions);

/// Sphere with smooth radial bumps, k = frequency:
///   r(d) = 1 + amplitude * (sin(k d.x) + sin(k d.y) + sin(k d.z)) / 3,
/// so r stays in [1 - |amplitude|, 1 + |amplitude|].
/// \pre |amplitude| < 1, 0 <= frequency <= 1000.
TriMesh bumpy_sphere(double amplitude, int frequency, int subdivisions);

/// Star-shaped blob with `arms` long thin protrusions, the kind of shape that forces quinary
/// splits: r(d) = 1 + arm_length * sum_i max(0, d . a_i)^48, with arm directions
/// a_i = fibonacci_directions(arms). Each arm is ~20 degrees wide at half its length and its tip
/// lies at radius ~1 + arm_length. Use subdivisions >= 4 to resolve the arms.
/// \pre 0 <= arms <= 1000, 0 <= arm_length <= 100.
TriMesh star_blob(int arms, double arm_length, int subdivisions);

/// `n` unit directions spread evenly over the sphere (Fibonacci / golden-angle spiral),
/// direction i at height z = 1 - (2i + 1) / n.
std::vector<Vec3> fibonacci_directions(int n);

/// Cube whose sides are split into n x n cells (two triangles each, equiangular spacing) and
/// projected to the unit sphere: 12 n^2 faces, 6 n^2 + 2 vertices. \pre 1 <= n <= 1024.
TriMesh cube_sphere(int n);

// ---- Negative cases for validation ----------------------------------------------------------

/// A flat hexagonal disk of radius 1 in the plane z = 0, cut into equilateral triangles with
/// `rings` triangles along each radius: 6 rings^2 faces, 3 rings (rings + 1) + 1 vertices, one
/// boundary loop of 6 * rings edges, faces counter-clockwise seen from +z. \pre 1 <= rings <= 1000.
TriMesh open_disk(int rings);

/// A torus (genus 1) about the z axis, tube centre radius 1, tube radius 0.4, outward-oriented:
/// `major` segments around the z axis times `minor` around the tube, each quad split in two:
/// 2 * major * minor faces, major * minor vertices. \pre 3 <= major, minor <= 4096.
TriMesh torus(int major, int minor);

/// Two disjoint unit icospheres (1 subdivision, 80 faces each), centred at the origin and at
/// (3, 0, 0). Vertices 0..41 and faces 0..79 are the first sphere.
TriMesh two_components();

/// A closed regular tetrahedron (vertices 0-3, faces 0-3, outward) with a fifth vertex and a
/// "fin" face 4 = (0, 1, 4) hung on its edge 0-1: edge 0-1 has three faces (non-manifold) and
/// the fin adds the two boundary edges 0-4 and 1-4.
TriMesh nonmanifold_fan();

}  // namespace qs::shapes
