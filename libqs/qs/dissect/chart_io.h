#pragma once
// The dissection's files, the contract the later tools and users' scripts rely on:
//  - <stem>.chart.ply: binary little-endian PLY of the cut mesh; per face `vertex_indices`,
//    `texcoord` (6 numbers: u,v of its 3 corners in its own patch, MeshLab's wedge texcoords;
//    float64 since chart version 2, float32 in version 1, which is still read),
//    `patch` (int, index into the patch list of dissection.json) and red/green/blue by patch.
//  - dissection.json: see dissection_to_json() and the README.

#include <filesystem>
#include <string>

#include "qs/dissect/dissection.h"

namespace qs::dissect {

/// 2: texcoords stored as float64 (qs-merge decides orientation and coincidence on them exactly);
/// 1: float32. The version is in a header comment; the reader tells them apart by the property.
inline constexpr int kChartFormatVersion = 2;

/// Writes the chart PLY atomically. \throws IoError.
void write_chart_ply(const std::filesystem::path& path, const Chart& chart);

/// Reads a chart PLY written by write_chart_ply, version 2 or 1 (patch infos other than the count are not in
/// the file: `patches` gets one default entry per patch label). \throws IoError, InvalidInput.
Chart read_chart_ply(const std::filesystem::path& path);

/// A distinct, stable colour per patch index (golden-ratio hue walk).
std::array<unsigned char, 3> patch_colour(int patch);

}  // namespace qs::dissect
