// A rigid cylinder (radius R) on an elastic block that stands for a half-space, 2D plane
// strain: the block 16 R wide and 8 R deep, the cylinder's lowest point `gap` above it, the
// third medium in a box around the cylinder's lower half. Cells of size h where the contact
// lies (|x| < R/2 on the block's top, and the cylinder's arc above it), growing to 2 R away.
SetFactory("OpenCASCADE");
DefineConstant[ R = 1, gap = 0.02, h = 0.01 ];
Rectangle(1) = {-8 * R, -8 * R, 0, 16 * R, 8 * R};        // block
Rectangle(2) = {-1.5 * R, 0, 0, 3 * R, 1.5 * R};          // medium box
Disk(3) = {0, R + gap, 0, R};                             // cylinder
all[] = BooleanFragments{ Surface{1, 2}; Delete; }{ Surface{3}; Delete; };
e = 1e-6;
block[] = Surface In BoundingBox{-8 * R - e, -8 * R - e, -e, 8 * R + e, e, e};
cylinder[] = Surface In BoundingBox{-R - e, gap - e, -e, R + e, 2 * R + gap + e, e};
medium[] = Surface{:};
medium[] -= {block[], cylinder[]};
Physical Surface("block") = block[];
Physical Surface("cylinder") = cylinder[];
Physical Surface("medium") = medium[];
Physical Curve("bottom") = Curve In BoundingBox{-8 * R - e, -8 * R - e, -e, 8 * R + e, -8 * R + e, e};
Physical Curve("rim") = Boundary{ Surface{cylinder[]}; };
// fine where the contact lies (|x| < R/2, |y| < R/10), the size growing over 3 R beyond
Field[1] = Box;
Field[1].VIn = h;
Field[1].VOut = 0.5 * R;
Field[1].XMin = -0.5 * R;
Field[1].XMax = 0.5 * R;
Field[1].YMin = -0.1 * R;
Field[1].YMax = 0.1 * R + gap;
Field[1].Thickness = 3 * R;
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
