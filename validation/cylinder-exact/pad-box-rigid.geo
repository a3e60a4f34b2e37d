// geo/pad-box.geo with one group more, "rim": the whole of the pad's boundary, so that a case
// can prescribe it and the pad moves as a rigid body (validation/cylinder-exact/README.md).
// A pad on a long plate in a box of medium, drawn as a user draws it: a plate L long and
// d thick, a pad w wide and 0.5 high a gap g above it, and the third medium filling a box
// 0.9 above the gap around the pad (OpenCASCADE, default triangles of size h). Groups: the
// solids "plate" and "pad", the medium "medium", the plate's held underside "bottom" and
// the pad's driven top "top". quads = 1 meshes quadrilaterals (gmsh's recombination)
// instead of triangles.
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.1, L = 7, w = 1, g = 0.1, d = 0.5, quads = 0 ];
Rectangle(1) = {0, 0, 0, L, d};
Rectangle(2) = {0, d, 0, L, g + 0.9};
Rectangle(3) = {0.5, d + g, 0, w, 0.5};
BooleanFragments{ Surface{1, 2}; Delete; }{ Surface{3}; Delete; }
e = 1e-6;
plate[] = Surface In BoundingBox{-e, -e, -e, L + e, d + e, e};
pad[] = Surface In BoundingBox{0.5 - e, d + g - e, -e, 0.5 + w + e, d + 0.5 + g + e, e};
all[] = Surface{:};
Physical Surface("plate") = {plate[]};
Physical Surface("pad") = {pad[]};
Physical Surface("medium") = {all[]};
Physical Surface("medium") -= {plate[], pad[]};
Physical Curve("bottom") = Curve In BoundingBox{-e, -e, -e, L + e, e, e};
Physical Curve("rim") = Boundary{ Surface{pad[]}; };
Physical Curve("top") = Curve In BoundingBox{0.5 - e, d + 0.5 + g - e, -e, 0.5 + w + e, d + 0.5 + g + e, e};
Mesh.MeshSizeMax = h;
If (quads)
  Mesh.RecombineAll = 1;
EndIf
