#pragma once
// The dissection's files, the contract the later tools and users' scripts rely on:
//  - <stem>.chart.ply: binary little-endian PLY of the cut mesh; per face `vertex_indices`,
//    `texcoord` (6 numbers: u,v of its 3 corners in its own patch, MeshLab's wedge texcoords;
//    float64 since chart version 2, float32 in version 1, which is still read),
//    `patch` (int, index into the patch list of dissection.json) and red/green/blue by patch.
//  - dissection.json: see dissection_to_json() and the README.

#include <filesystem>
#include <string>
#include <string_view>

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
/// The same from the file's bytes; `name` names the file in messages. Rejects counts that do not
/// match the bytes, vertex indices out of range, non-finite or too large (> 1e100) coordinates,
/// texcoords outside the unit square (1e-4 tolerance) or NaN, and patch ids outside [0, #F).
Chart parse_chart_ply(std::string_view data, const std::string& name);

/// The stem a chart file names its mesh by: "<stem>.chart.ply" -> "<stem>"; another name: its stem.
std::string chart_stem(const std::string& chart_file);

/// A distinct, stable colour per patch index (golden-ratio hue walk).
std::array<unsigned char, 3> patch_colour(int patch);

}  // namespace qs::dissect
