// Two blocks separated by a third-medium layer (Wriggers 2025, section 4.1.2).
// The paper gives no dimensions; we take: lower block 0 <= x <= W, 0 <= y <= H; medium
// H <= y <= H + t; upper block H + t <= y <= 2H + t, with W = 2, H = 1, t = 0.25 (the block
// scene's proportions). The upper block's top is split at x = W/2: "top_right" carries the load.
// Mesh: n cells along x, m rows per block, l rows in the medium, each quad split into two
// triangles (T1). n = 64, m = 32, l = 8 gives the paper's 9216 elements: the solids
// 64 x 64 and the medium 64 x 16 triangles.
DefineConstant[ W = 2.0, H = 1.0, t = 0.25, n = 64, m = 32, l = 8 ];
Point(1) = {0, 0, 0}; Point(2) = {W, 0, 0};
Point(3) = {W, H, 0}; Point(4) = {0, H, 0};
Point(5) = {W, H + t, 0}; Point(6) = {0, H + t, 0};
Point(7) = {W, 2 * H + t, 0}; Point(8) = {W / 2, 2 * H + t, 0}; Point(9) = {0, 2 * H + t, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {3, 5}; Line(6) = {5, 6}; Line(7) = {6, 4};
Line(8) = {5, 7}; Line(9) = {7, 8}; Line(10) = {8, 9}; Line(11) = {9, 6};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7}; Plane Surface(2) = {2};
Curve Loop(3) = {-6, 8, 9, 10, 11}; Plane Surface(3) = {3};
Transfinite Curve{1, 3, 6} = n + 1;
Transfinite Curve{9, 10} = n / 2 + 1;
Transfinite Curve{2, 4, 8, 11} = m + 1;
Transfinite Curve{5, 7} = l + 1;
Transfinite Surface{1}; Transfinite Surface{2};
Transfinite Surface{3} = {6, 5, 7, 9};
Physical Surface("lower") = {1};
Physical Surface("medium") = {2};
Physical Surface("upper") = {3};
Physical Curve("bottom") = {1};
Physical Curve("top_right") = {9};
Physical Curve("top_left") = {10};
