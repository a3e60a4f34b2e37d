// Two discs pressed by a half ellipse in a third-medium box (Wriggers 2025, section 4.1.3).
// The paper gives the shapes, not their places. Our choice: the box is -1 <= x <= 3,
// -1 <= y <= 2 (4 x 3), so that the half ellipse (x - 1)^2/4 + (y - 2)^2 = 0.9^2, y <= 2, hangs
// from the box's top with its flat side on it (-0.8 <= x <= 2.8). Below it sit the discs,
// 0.1 from the walls, the bottom and each other: r = 0.90 at (0, 0) and r = 0.95 at
// (1.95, 0.05). The ellipse's tip (1, 1.1) points into the slot between them; the right disc
// is 0.24 below the ellipse, the left one 0.35.
// Groups: "ellipse", "disc_left", "disc_right" (solids), "medium"; curves "ellipse_top" (the
// loaded flat side), "bottom", "left", "right" (box walls), "top" (the box's free top).
// Mesh: unstructured T1 of size h; h = 0.039 gives about 18 700 triangles (paper: 18 643).
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.039 ];
Rectangle(1) = {-1, -1, 0, 4, 3};
Disk(2) = {0, 0, 0, 0.90};
Disk(3) = {1.95, 0.05, 0, 0.95};
Disk(4) = {1, 2, 0, 1.8, 0.9};
BooleanIntersection(5) = { Surface{4}; Delete; }{ Surface{1}; };
BooleanFragments{ Surface{1}; Delete; }{ Surface{2, 3, 5}; Delete; }
e = 1e-6;
left() = Surface In BoundingBox{-0.9 - e, -0.9 - e, -1, 0.9 + e, 0.9 + e, 1};
right() = Surface In BoundingBox{1.0 - e, -0.9 - e, -1, 2.9 + e, 1.0 + e, 1};
ell() = Surface In BoundingBox{-0.8 - e, 1.1 - e, -1, 2.8 + e, 2 + e, 1};
all() = Surface{:};
medium() = all();
medium() -= left();
medium() -= right();
medium() -= ell();
Physical Surface("ellipse") = ell();
Physical Surface("disc_left") = left();
Physical Surface("disc_right") = right();
Physical Surface("medium") = medium();
Physical Curve("ellipse_top") = Curve In BoundingBox{-0.8 - e, 2 - e, -1, 2.8 + e, 2 + e, 1};
Physical Curve("bottom") = Curve In BoundingBox{-1 - e, -1 - e, -1, 3 + e, -1 + e, 1};
Physical Curve("left") = Curve In BoundingBox{-1 - e, -1 - e, -1, -1 + e, 2 + e, 1};
Physical Curve("right") = Curve In BoundingBox{3 - e, -1 - e, -1, 3 + e, 2 + e, 1};
top() = Curve In BoundingBox{-1 - e, 2 - e, -1, 3 + e, 2 + e, 1};
top() -= Curve In BoundingBox{-0.8 - e, 2 - e, -1, 2.8 + e, 2 + e, 1};
Physical Curve("top") = top();
Mesh.MeshSizeMax = h;
