// Plate 2 x 1 with a circular hole of radius r at its centre. cells = 2 (default): mixed mesh,
// the left half recombined into Q1 quads, the right half T1; cells = 0: T1 only; cells = 1:
// Q1 only (quads by subdivision). Left edge clamped, right edge pulled and heated.
DefineConstant[ r = 0.25, h = 0.08, cells = 2 ];
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 1, 1};
Rectangle(2) = {1, 0, 0, 1, 1};
Disk(3) = {1, 0.5, 0, r};
BooleanDifference{ Surface{1, 2}; Delete; }{ Surface{3}; Delete; }
Mesh.CharacteristicLengthMax = h;
e = 1e-6;
left() = Surface In BoundingBox{-e, -e, -e, 1 + e, 1 + e, e};
right() = Surface In BoundingBox{1 - e, -e, -e, 2 + e, 1 + e, e};
If (cells == 2)
  Recombine Surface{left()};
EndIf
If (cells == 1)
  Mesh.SubdivisionAlgorithm = 1;
  Recombine Surface{:};
EndIf
Physical Surface("solid") = Surface{:};
Physical Curve("left") = Curve In BoundingBox{-e, -e, -e, e, 1 + e, e};
Physical Curve("right") = Curve In BoundingBox{2 - e, -e, -e, 2 + e, 1 + e, e};
Physical Curve("hole") = Curve In BoundingBox{1 - r - e, 0.5 - r - e, -e, 1 + r + e, 0.5 + r + e, e};
