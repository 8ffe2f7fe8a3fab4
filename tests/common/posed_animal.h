#pragma once
// A generated animal and itself in another pose: the same faces, so vertex i <-> vertex i is the
// exact map (for the tests of registration and of dissections in other poses).

#include <cstdint>

#include "qs/dissect/dissection.h"
#include "qs/family/family.h"
#include "qs/family/pose.h"

namespace qs::test {

struct PosedAnimal {
  TriMesh a, b;                         ///< the animal, and its limbs bent and turned
  family::PoseLandmarks landmarks;      ///< vertex ids, valid on both
};

/// Four legs and a head, 4000 faces, generated with `seed` and posed at qs-family pose's defaults.
inline PosedAnimal posed_animal(std::uint64_t seed) {
  family::FamilyOptions o;
  o.shapes = 1;
  o.seed = seed;
  o.faces = 4000;
  o.limbs = 5;
  PosedAnimal out;
  out.a = family::generate_family(o).shapes[0].mesh;
  out.b = family::pose_mesh(out.a, {}).mesh;
  out.landmarks = family::choose_landmarks(out.a);
  return out;
}

/// `mesh` to dissect with the automatic landmarks `l` (seeds and features as vertex ids).
inline dissect::MeshToDissect with_landmarks(const TriMesh& mesh, const family::PoseLandmarks& l, const char* name) {
  dissect::MeshToDissect m;
  m.mesh = &mesh;
  m.seeds = std::array<int, 4>{l.seeds[0], l.seeds[1], l.seeds[2], l.seeds[3]};
  for (const auto& [feature, v] : l.features) m.features.push_back({feature, v, {}});
  m.name = name;
  return m;
}

}  // namespace qs::test
