// A unit cube meshed with 24 tetrahedra (4-node): the smallest tetrahedral test mesh.
//
// Regenerate: gmsh -3 -format msh41 tet.geo   (writes tet.msh)

SetFactory("OpenCASCADE");

Box(1) = {0, 0, 0, 1, 1, 1};
Mesh.MeshSizeMin = 1;
Mesh.MeshSizeMax = 1;

Physical Volume("body") = {1};
Physical Surface("top") = {6};

Mesh.SaveAll = 0;
Mesh.MshFileVersion = 4.1;
