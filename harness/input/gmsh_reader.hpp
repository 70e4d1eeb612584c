// Reader for Gmsh meshes in the ASCII .msh formats 2.2 and 4.1: 2D meshes (read_gmsh) and 3D ones
// (read_gmsh3), through the same tokenizer and sections.
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

// Reads a 3D mesh of 4-node tetrahedra (Gmsh type 4) and 8-node hexahedra (type 5), in Gmsh's
// corner order, which is VTK's (mesh.hpp); coordinates are taken as metres.
// - Nodes, cells and duplicates as read_gmsh: nodes renumbered in increasing tag, keeping only
//   nodes used by a cell; cells by element tag, hexahedra then tetrahedra in Mesh3.
// - Node sets: every physical group of points (15), lines (1), surfaces (2, 3) or volumes
//   becomes a node set, named as in read_gmsh.
// - Orientation: every cell must have positive volume; none is flipped.
// Throws InputError "FILE:LINE: what is wrong" as read_gmsh does, for the same file errors, any
// element type but 15, 1, 2, 3, 4, 5, cells of zero or negative volume, hexahedra with a corner
// Jacobian <= 0 (hex_corner_quality), or no tetrahedra or hexahedra at all.
Mesh3 read_gmsh3(const std::filesystem::path& file);
// The same for the TEXT of a .msh file; `name` stands for the file in messages.
Mesh3 parse_gmsh3(std::string text, const std::string& name);

// The dimension of the cells of a .msh file, for a case to know its dimension before it builds
// the mesh: 3 if it has tetrahedra or hexahedra (types 4, 5), else 2; 0 if it cannot be read or
// parsed (the mesh's reader, read_gmsh or read_gmsh3, then reports why).
int gmsh_dimension(const std::filesystem::path& file);

}  // namespace ricochet
