// Two-block contact benchmark, coarse: an upper block (0,2)x(0,1)x(1,2) resting on a lower block
// (0,2)x(0,1)x(0,1). The blocks are two independent volumes (no boolean fragments), so each body
// has its own nodes on the z = 1 interface. Structured: 7 x 4 x 4 nodes per block (6x3x3 hex8).
//
// Regenerate: gmsh -3 -format msh41 two_blocks.geo   (writes two_blocks.msh)

SetFactory("OpenCASCADE");

Box(1) = {0, 0, 1, 2, 1, 1}; // upper
Box(2) = {0, 0, 0, 2, 1, 1}; // lower

// Nodes per edge, by edge direction.
nx = 7; ny = 4; nz = 4;
crv() = Curve{:}; // (bounding boxes are padded by 1e-7, hence the 0.5 threshold)
For i In {0 : #crv() - 1}
  bb() = BoundingBox Curve{crv(i)};
  If (bb(3) - bb(0) > 0.5)
    Transfinite Curve{crv(i)} = nx;
  ElseIf (bb(4) - bb(1) > 0.5)
    Transfinite Curve{crv(i)} = ny;
  Else
    Transfinite Curve{crv(i)} = nz;
  EndIf
EndFor
Transfinite Surface{:};
Recombine Surface{:};
Transfinite Volume{:};

// OpenCASCADE numbers the faces of a box x=min, x=max, y=min, y=max, z=min, z=max.
Physical Volume("upper") = {1};
Physical Volume("lower") = {2};
Physical Surface("upper_top") = {6};
Physical Surface("upper_bottom") = {5};
Physical Surface("upper_left") = {1};
Physical Surface("upper_right") = {2};
Physical Surface("lower_top") = {12};
Physical Surface("lower_left") = {7};

Mesh.SaveAll = 0;
Mesh.MshFileVersion = 4.1;
