// A hemispherical slider on a plate through a third medium, for a drag along x: a half model
// (symmetry plane y = 0, the drag's own plane), tet4.
//   plate     -0.6 <= x <= 1.4, 0 <= y <= 0.7, 0 <= z <= 0.5
//   slider    the lower half of a ball of radius R = 0.4 centred at (0, 0, 1), cut at y = 0:
//             its flat top is the face z = 1, its lowest point (0, 0, 0.6) is 0.1 above the plate
//   medium    the rest of the box above the plate, up to z = 1
// The plate reaches x1 = 1.4 so that a drag of one radius ends 0.6 from its end (x1 = 2.2 for
// a drag of three radii).
// Groups: volumes "plate", "slider", "medium"; surfaces "bottom" (z = 0), "slider_top"
// (the slider's flat top), "y0" (the symmetry plane, all bodies).
// Mesh: tet4 of size h, h/2 in a box around the slider's path.
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.15, x1 = 1.4 ];
R = 0.4;
x0 = -0.6; w = 0.7;
Box(1) = {x0, 0, 0, x1 - x0, w, 0.5};
Box(2) = {x0, 0, 0.5, x1 - x0, w, 0.5};
Sphere(3) = {0, 0, 1, R};
Box(4) = {-R, 0, 0.5, 2 * R, R, 0.5};
BooleanIntersection(5) = { Volume{3}; Delete; }{ Volume{4}; Delete; };
BooleanFragments{ Volume{1, 2}; Delete; }{ Volume{5}; Delete; }
e = 1e-6;
plate() = Volume In BoundingBox{x0 - e, -e, -e, x1 + e, w + e, 0.5 + e};
slider() = Volume In BoundingBox{-R - e, -e, 1 - R - e, R + e, R + e, 1 + e};
medium() = Volume{:};
medium() -= plate();
medium() -= slider();
Physical Volume("plate") = plate();
Physical Volume("slider") = slider();
Physical Volume("medium") = medium();
Physical Surface("bottom") = Surface In BoundingBox{x0 - e, -e, -e, x1 + e, w + e, e};
Physical Surface("slider_top") = Surface In BoundingBox{-R - e, -e, 1 - e, R + e, R + e, 1 + e};
Physical Surface("y0") = Surface In BoundingBox{x0 - e, -e, -e, x1 + e, e, 1 + e};
Mesh.MeshSizeMax = h;
Field[1] = Box;
Field[1].XMin = -0.3; Field[1].XMax = 0.7;
Field[1].YMin = -0.1; Field[1].YMax = 0.3;
Field[1].ZMin = 0.4; Field[1].ZMax = 0.7;
Field[1].VIn = h / 2;
Field[1].VOut = h;
Field[1].Thickness = 0.2;
Background Field = 1;
