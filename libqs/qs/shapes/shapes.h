#pragma once
// Meshes made in code, for tests, examples and benchmarks. All closed ones are outward-oriented,
// manifold and genus 0 unless named otherwise.

#include "qs/core/mesh.h"

namespace qs::shapes {

/// Unit icosphere: 20 * 4^subdivisions faces.
TriMesh icosphere(int subdivisions);
/// Icosphere scaled to semi-axes (a, b, c).
TriMesh ellipsoid(double a, double b, double c, int subdivisions);
/// Sphere with smooth radial bumps r = 1 + amplitude * sin(k theta) sin(k phi)-style noise.
TriMesh bumpy_sphere(double amplitude, int frequency, int subdivisions);
/// Star-shaped blob with `arms` long protrusions (length ~ arm_length times the body radius):
/// the kind of shape that forces quinary splits.
TriMesh star_blob(int arms, double arm_length, int subdivisions);
/// Cube subdivided n x n per side and projected to the unit sphere: 12 n^2 faces.
TriMesh cube_sphere(int n);

// Negative cases for validation.
/// A flat open disk (one boundary loop of `rings`*6 edges... see .cpp).
TriMesh open_disk(int rings);
/// A torus (genus 1), `major` x `minor` quads split in two.
TriMesh torus(int major, int minor);
/// Two disjoint icospheres.
TriMesh two_components();
/// Three triangles sharing one edge (a non-manifold edge) closed up otherwise as much as possible.
TriMesh nonmanifold_fan();

}  // namespace qs::shapes
