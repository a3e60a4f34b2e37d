// A block on a third-medium layer in 3D (the block scene of block.geo extruded across y):
// medium 0 <= z <= t, solid t <= z <= t + H, both over 0 <= x <= W, 0 <= y <= B; structured
// H1 mesh with n cells along x, nb along y, l through the medium and m through the solid;
// tet = 1 splits each hexahedron into six tetrahedra (a friction layer of tetrahedra can be
// closed under the block's leading corner and open beyond it, which a hexahedron cannot).
DefineConstant[ W = 2.0, B = 1.0, H = 1.0, t = 0.25, n = 8, nb = 4, m = 4, l = 2, tet = 0 ];
Point(1) = {0, 0, 0}; Point(2) = {W, 0, 0}; Point(3) = {W, B, 0}; Point(4) = {0, B, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 3} = n + 1;
Transfinite Curve{2, 4} = nb + 1;
Transfinite Surface{1};
If (tet == 0)
  Recombine Surface{1};
EndIf
// each extruded surface yields {top, volume, 4 sides}
If (tet == 0)
  md[] = Extrude {0, 0, t} { Surface{1}; Layers{l}; Recombine; };
  sd[] = Extrude {0, 0, H} { Surface{md[0]}; Layers{m}; Recombine; };
Else
  md[] = Extrude {0, 0, t} { Surface{1}; Layers{l}; };
  sd[] = Extrude {0, 0, H} { Surface{md[0]}; Layers{m}; };
EndIf
Physical Volume("medium") = {md[1]};
Physical Volume("solid") = {sd[1]};
Physical Surface("bottom") = {1};
Physical Surface("top") = {sd[0]};
