// Block and plate with a third-medium layer between (Wriggers 2025, section 4.2), one quarter
// (x, y >= 0; symmetry planes x = 0 and y = 0). Block 4 x 4 x 2 (0 <= z <= 2), medium
// 4 x 4 x 0.5 (2 <= z <= 2.5), plate 4 x 4 x 1 (2.5 <= z <= 3.5); the loaded 4 x 4 patch of the
// full model is the corner 0 <= x, y <= 2 of the plate's top.
// Structured H1 mesh: n x n cells in plan (n even, so the patch edge lies on nodes) and nb,
// nm, nq layers through block, medium and plate. The paper gives 8 x 8 x 10 and 16 x 16 x 20
// meshes without the split of the layers; we take nb = 5, nm = 2, nq = 3 (element heights
// 0.4, 0.25, 0.33, close to the plan size 0.5) and scale them with n.
DefineConstant[ n = 8, nb = 5, nm = 2, nq = 3 ];
a = 4; c = 2; hb = 2; hm = 0.5; hq = 1;
Point(1) = {0, 0, 0}; Point(2) = {c, 0, 0}; Point(3) = {a, 0, 0};
Point(4) = {0, c, 0}; Point(5) = {c, c, 0}; Point(6) = {a, c, 0};
Point(7) = {0, a, 0}; Point(8) = {c, a, 0}; Point(9) = {a, a, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {4, 5}; Line(4) = {5, 6};
Line(5) = {7, 8}; Line(6) = {8, 9};
Line(7) = {1, 4}; Line(8) = {4, 7}; Line(9) = {2, 5}; Line(10) = {5, 8};
Line(11) = {3, 6}; Line(12) = {6, 9};
Curve Loop(1) = {1, 9, -3, -7}; Plane Surface(1) = {1};
Curve Loop(2) = {2, 11, -4, -9}; Plane Surface(2) = {2};
Curve Loop(3) = {3, 10, -5, -8}; Plane Surface(3) = {3};
Curve Loop(4) = {4, 12, -6, -10}; Plane Surface(4) = {4};
Transfinite Curve{1:12} = n / 2 + 1;
Transfinite Surface{1:4};
Recombine Surface{1:4};
// each extruded quad yields {top, volume, 4 sides}
b[] = Extrude {0, 0, hb} { Surface{1:4}; Layers{nb}; Recombine; };
m[] = Extrude {0, 0, hm} { Surface{b[0], b[6], b[12], b[18]}; Layers{nm}; Recombine; };
q[] = Extrude {0, 0, hq} { Surface{m[0], m[6], m[12], m[18]}; Layers{nq}; Recombine; };
Physical Volume("block") = {b[1], b[7], b[13], b[19]};
Physical Volume("medium") = {m[1], m[7], m[13], m[19]};
Physical Volume("plate") = {q[1], q[7], q[13], q[19]};
Physical Surface("patch") = {q[0]};
e = 1e-6;
Physical Surface("bottom") = Surface In BoundingBox {-e, -e, -e, a + e, a + e, e};
Physical Surface("x0") = Surface In BoundingBox {-e, -e, -e, e, a + e, 3.5 + e};
Physical Surface("y0") = Surface In BoundingBox {-e, -e, -e, a + e, e, 3.5 + e};
