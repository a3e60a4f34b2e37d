// Block on a third-medium layer (Wriggers 2025, section 4.1.1).
// Medium 0 <= y <= t, solid t <= y <= t + H, both 0 <= x <= W; structured Q1 mesh.
// Parameters (tmc mesh --set name=value): n cells along x, m across the solid, l across
// the medium. The paper's mesh is n = m = 32, l = 8. skew != 1 grades the cells along the
// medium's bottom and top in opposite directions (ratio skew from cell to cell), which
// distorts the medium's cells into slanted trapezoids (a test of distorted meshes). tri = 1
// cuts each cell into two triangles along the same diagonal, tri = 2 alternates the diagonal
// from cell to cell (a friction layer's leading corner then sits in either kind: THEORY.md,
// "The block with one cell across").
DefineConstant[ W = 2.0, H = 1.0, t = 0.25, n = 32, m = 32, l = 8, tri = 0, skew = 1 ];
Point(1) = {0, 0, 0}; Point(2) = {W, 0, 0}; Point(3) = {W, t, 0}; Point(4) = {0, t, 0};
Point(5) = {W, t + H, 0}; Point(6) = {0, t + H, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {3, 5}; Line(6) = {5, 6}; Line(7) = {6, 4};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {-3, 5, 6, 7}; Plane Surface(2) = {2};
Transfinite Curve{1, 3} = n + 1 Using Progression skew;
Transfinite Curve{6} = n + 1;
Transfinite Curve{2, 4} = l + 1;
Transfinite Curve{5, 7} = m + 1;
If (tri == 2)
  Transfinite Surface{1} Alternate; Transfinite Surface{2} Alternate;
Else
  Transfinite Surface{1}; Transfinite Surface{2};
EndIf
If (tri == 0)
  Recombine Surface{1, 2};
EndIf
Physical Surface("medium") = {1};
Physical Surface("solid") = {2};
Physical Curve("bottom") = {1};
Physical Curve("top") = {6};
Physical Curve("interface") = {3};
// the solid's sides and its lower-left corner (for tests that stretch the solid)
Physical Curve("solid_left") = {7};
Physical Curve("solid_right") = {5};
Physical Point("corner") = {4};
// the medium's sides (free in cases/block.toml)
Physical Curve("medium_left") = {4};
Physical Curve("medium_right") = {2};
