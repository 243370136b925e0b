// The tutorial's model (docs/tutorial.md): a cylindrical steel punch standing on a block.
// Two volumes meshed apart (no shared nodes: the contact faces do not match, so the solver
// couples them by dual mortar), Gmsh's default 4-node tetrahedra, lengths in metres.
//
// Regenerate: gmsh -3 -format msh41 tutorial.geo -o tutorial.msh

SetFactory("OpenCASCADE");

Box(1) = {0, 0, 0, 1, 1, 0.5};                  // the block: 1 × 1 × 0.5
Cylinder(2) = {0.5, 0.5, 0.5, 0, 0, 0.4, 0.25};  // the punch: radius 0.25, height 0.4, on top

// Element sizes: the punch finer than the block.
MeshSize{ PointsOf{ Volume{1}; } } = 0.1;
MeshSize{ PointsOf{ Volume{2}; } } = 0.05;

// The punch's flat ends, found by their bounding boxes.
punch() = Boundary{ Volume{2}; };
For i In {0 : #punch() - 1}
  bb() = BoundingBox Surface{ punch(i) };
  If (bb(5) - bb(2) < 1e-6)
    If (bb(2) < 0.6)
      punch_bottom = punch(i);
    Else
      punch_top = punch(i);
    EndIf
  EndIf
EndFor

// Named groups: the scene refers to them as body.name (tutorial.toml).
// OpenCASCADE numbers a box's faces x = min, x = max, y = min, y = max, z = min, z = max.
Physical Volume("block") = {1};
Physical Volume("punch") = {2};
Physical Surface("block_bottom") = {5};
Physical Surface("block_top") = {6};
Physical Surface("punch_bottom") = {punch_bottom};
Physical Surface("punch_top") = {punch_top};

Mesh.SaveAll = 0;          // only the physical groups
Mesh.MshFileVersion = 4.1;
Mesh.RandomSeed = 1;
