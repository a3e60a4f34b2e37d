// Slab 0 <= x <= L, 0 <= y <= H, structured Q1 mesh.
// Parameters (override with `tmc mesh --set n=...`): n cells along x, m along y.
DefineConstant[ L = 2.0, H = 1.0, n = 8, m = 4 ];
Point(1) = {0, 0, 0}; Point(2) = {L, 0, 0}; Point(3) = {L, H, 0}; Point(4) = {0, H, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve{1, 3} = n + 1; Transfinite Curve{2, 4} = m + 1;
Transfinite Surface{1}; Recombine Surface{1};
Physical Surface("solid") = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Point("origin") = {1};
