// A hemispherical indenter pressed into a block through a third medium: tmc's own 3D scene,
// a quarter model (symmetry planes x = 0 and y = 0). Built with OpenCASCADE booleans and
// meshed with tet4, to show that curved 3D contact needs nothing but physical groups.
//   block     0 <= x, y <= 1, 0 <= z <= 0.5
//   indenter  the lower half of a ball of radius R = 0.4 centred at (0, 0, 1): its flat top
//             is the top face z = 1, its lowest point (0, 0, 0.6) is 0.1 above the block
//   medium    the rest of the box 0 <= x, y <= 1, 0.5 <= z <= 1
// Groups: volumes "block", "indenter", "medium"; surfaces "bottom" (z = 0), "indenter_top"
// (the indenter's flat top), "x0", "y0" (symmetry planes, all bodies).
// Mesh: tet4 of size h (h = 0.05: about 60 000 tets), finer (h/2) near the indenter's tip.
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.05 ];
R = 0.4;
Box(1) = {0, 0, 0, 1, 1, 0.5};
Box(2) = {0, 0, 0.5, 1, 1, 0.5};
Sphere(3) = {0, 0, 1, R};
Box(4) = {0, 0, 0.5, 1, 1, 0.5};
BooleanIntersection(5) = { Volume{3}; Delete; }{ Volume{4}; Delete; };
BooleanFragments{ Volume{1, 2}; Delete; }{ Volume{5}; Delete; }
e = 1e-6;
blk() = Volume In BoundingBox{-e, -e, -e, 1 + e, 1 + e, 0.5 + e};
ind() = Volume In BoundingBox{-e, -e, 1 - R - e, R + e, R + e, 1 + e};
all() = Volume{:};
med() = all();
med() -= blk();
med() -= ind();
Physical Volume("block") = blk();
Physical Volume("indenter") = ind();
Physical Volume("medium") = med();
Physical Surface("bottom") = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};
Physical Surface("indenter_top") = Surface In BoundingBox{-e, -e, 1 - e, R + e, R + e, 1 + e};
Physical Surface("x0") = Surface In BoundingBox{-e, -e, -e, e, 1 + e, 1 + e};
Physical Surface("y0") = Surface In BoundingBox{-e, -e, -e, 1 + e, e, 1 + e};
Mesh.MeshSizeMax = h;
Field[1] = Ball;
Field[1].Radius = 0.3;
Field[1].XCenter = 0; Field[1].YCenter = 0; Field[1].ZCenter = 0.55;
Field[1].VIn = h / 2;
Field[1].VOut = h;
Background Field = 1;
