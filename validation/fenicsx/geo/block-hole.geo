// FEniCSx validation, 3D: a block 1 x 0.6 x 0.4 with a cylindrical hole of radius r along z
// through (0.5, 0.3). hex = 1: the face z = 0 meshed in quads and extruded in nz layers (H1);
// hex = 0: unstructured tet4.
DefineConstant[ r = 0.15, h = 0.1, nz = 3, hex = 0 ];
SetFactory("OpenCASCADE");
Mesh.CharacteristicLengthMax = h;
e = 1e-6;
If (hex == 1)
  Rectangle(1) = {0, 0, 0, 1, 0.6};
  Disk(2) = {0.5, 0.3, 0, r};
  BooleanDifference{ Surface{1}; Delete; }{ Surface{2}; Delete; }
  Recombine Surface{:};
  Extrude {0, 0, 0.4} { Surface{:}; Layers{nz}; Recombine; }
EndIf
If (hex == 0)
  Box(1) = {0, 0, 0, 1, 0.6, 0.4};
  Cylinder(2) = {0.5, 0.3, 0, 0, 0, 0.4, r};
  BooleanDifference{ Volume{1}; Delete; }{ Volume{2}; Delete; }
EndIf
Physical Volume("solid") = Volume{:};
Physical Surface("x0") = Surface In BoundingBox{-e, -e, -e, e, 0.6 + e, 0.4 + e};
Physical Surface("x1") = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 0.6 + e, 0.4 + e};
