// A pad on a long plate: a solid pad (P wide, H high) pressed onto a third-medium layer
// (t thick) that runs a distance a beyond the pad on both sides, so that a pad dragged
// along x meets open medium ahead of it (the medium is ploughed) and leaves it behind. The
// layer's bottom is the plate's surface (group "bottom", held in the cases). Structured Q1
// mesh: n cells across the pad, as many per length beyond it, m through the pad, l through
// the medium; tri = 1 splits each cell into two triangles (T1).
DefineConstant[ P = 2.0, H = 1.0, t = 0.25, a = 1.0, n = 16, m = 8, l = 4, tri = 0 ];
na = Round(n * a / P);
Point(1) = {0, 0, 0}; Point(2) = {a, 0, 0}; Point(3) = {a + P, 0, 0};
Point(4) = {2 * a + P, 0, 0};
Point(5) = {0, t, 0}; Point(6) = {a, t, 0}; Point(7) = {a + P, t, 0}; Point(8) = {2 * a + P, t, 0};
Point(9) = {a, t + H, 0}; Point(10) = {a + P, t + H, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4};
Line(4) = {5, 6}; Line(5) = {6, 7}; Line(6) = {7, 8};
Line(7) = {1, 5}; Line(8) = {2, 6}; Line(9) = {3, 7}; Line(10) = {4, 8};
Line(11) = {6, 9}; Line(12) = {9, 10}; Line(13) = {10, 7};
Curve Loop(1) = {1, 8, -4, -7}; Plane Surface(1) = {1};
Curve Loop(2) = {2, 9, -5, -8}; Plane Surface(2) = {2};
Curve Loop(3) = {3, 10, -6, -9}; Plane Surface(3) = {3};
Curve Loop(4) = {5, -13, -12, -11}; Plane Surface(4) = {4};
Transfinite Curve{1, 3, 4, 6} = na + 1;
Transfinite Curve{2, 5, 12} = n + 1;
Transfinite Curve{7, 8, 9, 10} = l + 1;
Transfinite Curve{11, 13} = m + 1;
Transfinite Surface{1, 2, 3, 4};
If (tri == 0)
  Recombine Surface{1, 2, 3, 4};
EndIf
Physical Surface("medium") = {1, 2, 3};
Physical Surface("solid") = {4};
Physical Curve("bottom") = {1, 2, 3};
Physical Curve("top") = {12};
// the pad's bottom face and the open medium's top ahead of and behind it
Physical Curve("interface") = {5};
Physical Curve("medium_top") = {4, 6};
