#pragma once
// Topology control of a frame's field: the inside set grown from its deepest sample by adding
// only simple points, so that the polygonized frame is one closed genus-0 surface.
//
// The polygonizer (polygonize.h) triangulates every cell into the 6 Kuhn tetrahedra; its zero set
// bounds a region homotopy equivalent to the subcomplex of that triangulation spanned by the
// inside (negative) samples, whose edges join a sample to its 14 neighbours (offsets in
// {0,1}^3 and their negatives). A sample is simple for a set S when adding it changes neither the
// topology of S nor of its complement: the neighbours in S, joined along the edges of the sample's
// link (two neighbours are joined when they are neighbours of each other; the link is a
// triangulated sphere), form one non-empty connected piece, and so do the neighbours not in S
// (Alexander duality on the link: then the part in S is contractible). This is the simple-point
// test of digital topology (Bertrand and Malandain's 26/6 test for the cube lattice) for the
// lattice the polygonizer uses, so no 26/6 mismatch can slip a handle through.
//
// Growing from one sample, in order of the field value (deepest first), and adding a sample only
// while it is simple keeps the grown set contractible: the zero set of the result is one sphere.
// Inside samples not added (the last samples that would close a handle or a cavity, and every
// other component) are set just outside.

#include <cstddef>

#include "qs/dfi/grid.h"
#include "qs/dfi/polygonize.h"

namespace qs::dfi {

/// The 7 non-zero offsets in {0,1}^3 and their negatives: the edges of the Kuhn tetrahedra, i.e.
/// the neighbours that the polygonizer's surface joins (neighbour n is bit n of a mask below).
inline constexpr int kNeighbours14[14][3] = {{1, 0, 0},   {0, 1, 0},   {0, 0, 1},    {1, 1, 0},  {1, 0, 1},
                                             {0, 1, 1},   {1, 1, 1},   {-1, 0, 0},   {0, -1, 0}, {0, 0, -1},
                                             {-1, -1, 0}, {-1, 0, -1}, {0, -1, -1}, {-1, -1, -1}};

struct BallOptions {
  /// Value (in cells) given to inside samples that are not added: just outside, so the surface
  /// passes close to them. Must exceed the polygonizer's snap tolerance.
  double outside_value = 0.05;
};

struct BallReport {
  size_t inside = 0;   ///< inside samples before (as the polygonizer counts them: below -snap tolerance)
  size_t removed = 0;  ///< inside samples set outside
  size_t components_removed = 0;  ///< inside components (14-connected) that the growth did not reach
};

/// True when a sample whose 14 neighbours are in S as `mask` says (bit n for neighbour n of
/// kNeighbours14) is simple for S: both the neighbours in S and those not in S are non-empty and
/// connected along the link's edges.
bool is_simple_14(unsigned mask);

/// The 14 neighbour offsets of the polygonizer's lattice, in the order of is_simple_14's bits.
extern const int kNeighbours14[14][3];

/// Makes the inside set of `field` (samples below -snap tolerance, as polygonize counts them)
/// a topological ball: grown from its lowest sample (the lowest index among equals) in order of
/// (value, index), adding a sample only when it is simple; every inside sample not added is set
/// to +outside_value cells. A field with no inside sample is left as it is. Deterministic
/// (sequential). \throws InvalidInput when outside_value is not above the snap tolerance.
BallReport make_ball(Grid& field, const BallOptions& options = {}, const PolygonizeOptions& polygonize = {});

}  // namespace qs::dfi
