// Box [0, 1] x [0, 0.6] x [0, 0.4] meshed with unstructured tet4.
DefineConstant[ h = 0.2 ];
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.6, 0.4};
Mesh.CharacteristicLengthMax = h;
e = 1e-6;
Physical Volume("solid") = {1};
Physical Surface("x0") = Surface In BoundingBox{-e, -e, -e, e, 1, 1};
Physical Surface("x1") = Surface In BoundingBox{1 - e, -e, -e, 1 + e, 1, 1};
Physical Surface("y0") = Surface In BoundingBox{-e, -e, -e, 2, e, 1};
Physical Surface("z0") = Surface In BoundingBox{-e, -e, -e, 2, 1, e};
Physical Surface("boundary") = Surface{:};
