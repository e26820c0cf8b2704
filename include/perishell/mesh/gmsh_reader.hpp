#pragma once
// Gmsh MSH 4.1 ASCII import of a shell mesh of quads and triangles with its physical groups
// as named sets.
//
// Read: $MeshFormat (4.1, ASCII), $PhysicalNames, $Entities, $Nodes, $Elements; other
// sections ($Periodic, $NodeData, ...) are skipped. Elements: 4-node quads (type 3) and
// 3-node triangles (type 2, stored as a b c c: mesh/quad_mesh.hpp) become the mesh, in any
// mix; on physical curves, 2-node lines (type 1) become edge sets; on physical points,
// points (type 15) become node sets. Lines and points on entities without a physical group
// carry no set and are ignored; every other element type is rejected (second-order and
// volume elements: not a first-order shell mesh).
//
// Sets: a physical surface gives an element set and the node set of its quads' nodes; a
// physical curve an edge set (each edge ordered as its quad traverses it) and the node set
// of its nodes; a physical point a node set. Names come from $PhysicalNames; an unnamed
// group is called "point-<tag>", "curve-<tag>" or "surface-<tag>". Groups of different
// dimensions with the same name merge into one node set.
//
// Nodes: Gmsh tags map to 0-based indices in file order, keeping only nodes of quads (files
// saved with Mesh.SaveAll = 0 list nodes of boundary entities and have gaps in the tags).
// Orientation: quads sharing an edge are made to traverse it in opposite directions, each
// connected patch keeping the orientation of its first quad in the file (Gmsh surfaces may
// be oriented independently); a non-orientable surface is an error.
//
// Every error throws std::runtime_error "<file>:<line>: <reason>" (line 0: the file as a
// whole, e.g. it cannot be opened).
#include <perishell/mesh/mesh_sets.hpp>

#include <string>

namespace perishell::mesh {

ShellMesh readGmsh(const std::string& path);

// The same from text in memory; sourceName stands for the file in error messages.
ShellMesh parseGmsh(const std::string& text, const std::string& sourceName);

}  // namespace perishell::mesh
