// A cylinder pressed onto a plate, 2D plane strain: the plate 2 x 0.5, the cylinder (radius
// R, 0.4 unless set) 0.1 above it, the third medium filling a box 0.1 higher than it.
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.05, R = 0.4 ];      // mesh size: tmc mesh --set h=0.1, or [mesh_options]
Rectangle(1) = {0, 0, 0, 2, 0.5};         // plate
Rectangle(2) = {0, 0.5, 0, 2, 2*R + 0.2}; // the space above it
Disk(3) = {1, 0.6 + R, 0, R};             // cylinder, 0.1 above the plate
all[] = BooleanFragments{ Surface{1, 2}; Delete; }{ Surface{3}; Delete; };
e = 1e-6;
plate[] = Surface In BoundingBox{-e, -e, -e, 2 + e, 0.5 + e, e};
cylinder[] = Surface In BoundingBox{1 - R - e, 0.6 - e, -e, 1 + R + e, 0.6 + 2*R + e, e};
medium[] = Surface{:};
medium[] -= {plate[], cylinder[]};
Physical Surface("plate") = plate[];
Physical Surface("cylinder") = cylinder[];
Physical Surface("medium") = medium[];
Physical Curve("bottom") = Curve In BoundingBox{-e, -e, -e, 2 + e, e, e};
Physical Curve("rim") = Boundary{ Surface{cylinder[]}; };
Mesh.MeshSizeMax = h;
