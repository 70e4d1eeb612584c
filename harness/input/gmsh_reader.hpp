// Reader for 2D Gmsh meshes in the ASCII .msh formats 2.2 and 4.1.
#pragma once

#include <filesystem>
#include <string>

#include "solver/model/mesh.hpp"

namespace ricochet {

// Reads a planar (z = 0) mesh of 3-node triangles (Gmsh type 2) and 4-node quadrangles
// (type 3); coordinates are taken as metres.
// - Nodes are renumbered in increasing Gmsh node tag, keeping only nodes used by a cell.
//   Cells are ordered by Gmsh element tag; in 2.2 files, a cell repeated with the same nodes
//   (Gmsh writes one copy per physical group) is kept once.
// - Node sets: every physical group of points (type 15), lines (type 1) or cells becomes a
//   node set holding the nodes of its elements that belong to cells. It is named from
//   $PhysicalNames, or "physical_<tag>" if unnamed; groups that share a name are merged.
// - Orientation: if every cell is clockwise, all are flipped to counter-clockwise.
// Throws InputError "FILE:LINE: what is wrong" (or "FILE: ..." when no line applies) for an
// unreadable or malformed file, a binary file, another version, any other element type,
// nodes off z = 0, zero-area or non-convex cells, mixed orientation, or no cells at all.
Mesh read_gmsh(const std::filesystem::path& file);
// The same for the TEXT of a .msh file; `name` stands for the file in messages.
Mesh parse_gmsh(std::string text, const std::string& name);

}  // namespace ricochet
