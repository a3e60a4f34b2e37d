// Bar [0, L] x [0, B] x [0, B], structured H1 (hex8) mesh.
// Symmetry planes x0, y0, z0 let a uniaxial load contract the bar freely.
DefineConstant[ L = 2.0, B = 0.5, n = 8, m = 2 ];
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, L, B, B};
Transfinite Curve{:} = m + 1;
Transfinite Curve{Curve{:}} = m + 1;
// curves along x get n cells
e = 1e-6;
cx() = Curve In BoundingBox{-e, -e, -e, L + e, e, e};
cx() += Curve In BoundingBox{-e, B - e, -e, L + e, B + e, e};
cx() += Curve In BoundingBox{-e, -e, B - e, L + e, e, B + e};
cx() += Curve In BoundingBox{-e, B - e, B - e, L + e, B + e, B + e};
Transfinite Curve{cx()} = n + 1;
Transfinite Surface{:};
Recombine Surface{:};
Transfinite Volume{1};
Physical Volume("solid") = {1};
Physical Surface("x0") = Surface In BoundingBox{-e, -e, -e, e, B + e, B + e};
Physical Surface("x1") = Surface In BoundingBox{L - e, -e, -e, L + e, B + e, B + e};
Physical Surface("y0") = Surface In BoundingBox{-e, -e, -e, L + e, e, B + e};
Physical Surface("y1") = Surface In BoundingBox{-e, B - e, -e, L + e, B + e, B + e};
Physical Surface("z0") = Surface In BoundingBox{-e, -e, -e, L + e, B + e, e};
Physical Surface("z1") = Surface In BoundingBox{-e, -e, B - e, L + e, B + e, B + e};
