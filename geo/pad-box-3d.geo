// A square pad on a plate in a box of medium, in 3D: one half (y >= 0, the plane y = 0 a
// plane of symmetry). A plate L long, W wide (the half) and d thick; a pad w x w (its half
// w/2 wide) and 0.5 high a gap g above it; the third medium filling a box 0.9 above the gap
// over the whole plate (OpenCASCADE, tetrahedra of size h; hp > 0 meshes the pad at hp, so
// that its nodes and the plate's do not stand over each other all at once as it slides).
// Groups: the solids "plate" and "pad", the medium "medium", the plate's held underside
// "bottom", the pad's driven top "top" and the symmetry plane "y0".
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.2, hp = 0, L = 3, W = 1, w = 1, g = 0.1, d = 0.5 ];
Box(1) = {0, 0, 0, L, W, d};
Box(2) = {0, 0, d, L, W, g + 0.9};
Box(3) = {0.5, 0, d + g, w, w / 2, 0.5};
BooleanFragments{ Volume{1, 2}; Delete; }{ Volume{3}; Delete; }
e = 1e-6;
plate[] = Volume In BoundingBox{-e, -e, -e, L + e, W + e, d + e};
pad[] = Volume In BoundingBox{0.5 - e, -e, d + g - e, 0.5 + w + e, w / 2 + e, d + g + 0.5 + e};
all[] = Volume{:};
Physical Volume("plate") = {plate[]};
Physical Volume("pad") = {pad[]};
Physical Volume("medium") = {all[]};
Physical Volume("medium") -= {plate[], pad[]};
Physical Surface("bottom") = Surface In BoundingBox{-e, -e, -e, L + e, W + e, e};
Physical Surface("top") = Surface In BoundingBox{0.5 - e, -e, d + g + 0.5 - e, 0.5 + w + e, w / 2 + e, d + g + 0.5 + e};
Physical Surface("y0") = Surface In BoundingBox{-e, -e, -e, L + e, e, d + g + 0.9 + e};
Mesh.MeshSizeMax = h;
If (hp > 0)
  MeshSize{ PointsOf{ Volume{pad[]}; } } = hp;
EndIf
