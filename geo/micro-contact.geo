// Two rough surfaces joined by a third medium (Wriggers 2025, section 4.1.4, micro scale).
// The paper gives no profile. Ours, on 0 <= x <= 4 (g(c, w) = exp(-((x - c)/w)^2)):
//   lower body 0 <= y <= y_l, y_l = 2 + 0.09 g(1, 0.5) + 0.05 g(3, 0.55) + 0.01 sin(3 pi x)
//   upper body y_u <= y <= 4.72, y_u = 2.72 - 0.11 g(1.1, 0.5) - 0.12 g(2.9, 0.5)
//                                        + 0.01 sin(5 pi x + 0.5)
// and the medium between them. Asperities of different heights: the gap y_u - y_l is 0.517 at
// x = 1.04 and 0.549 at x = 2.98 (the two first contact spots), 0.67 to 0.72 elsewhere, so
// that a top displacement of 1/3 closes nothing, 2/3 closes the two spots and 4/3 everything.
// The asperities are broad (width ~1) and the bodies tall (2): the approach after the first
// contact is spread over a large volume. (Narrow asperities, 0.2 wide, were crushed to
// J ~ 0.55 before full contact and crease: a true bifurcation of the solid, where a
// displacement-driven quasi-static solve must stop.)
// Groups: "lower", "upper" (solids), "medium"; curves "bottom", "top", "left", "right" (the
// whole sides, bodies and medium).
// Mesh: T1 throughout. The medium is structured, np cells along x by l across (each quad cut
// into two triangles), so that its cells shrink evenly as the gap closes; the bodies are
// unstructured, of size h at the surfaces and 4 h at the far edges.
// np = 100, l = 6, h = 0.04: about 11 000 triangles.
DefineConstant[ h = 0.04, np = 100, l = 6 ];
Point(1) = {0, 0, 0, 4 * h}; Point(2) = {4, 0, 0, 4 * h};
Point(3) = {4, 4.72, 0, 4 * h}; Point(4) = {0, 4.72, 0, 4 * h};
For i In {0:np}
  x = 4 * i / np;
  yl = 2 + 0.09 * Exp(-((x - 1) / 0.5)^2) + 0.05 * Exp(-((x - 3) / 0.55)^2)
       + 0.01 * Sin(3 * Pi * x);
  yu = 2.72 - 0.11 * Exp(-((x - 1.1) / 0.5)^2) - 0.12 * Exp(-((x - 2.9) / 0.5)^2)
       + 0.01 * Sin(5 * Pi * x + 0.5);
  Point(100 + i) = {x, yl, 0, h};
  Point(1000 + i) = {x, yu, 0, h};
  lower[i] = 100 + i;
  upper[i] = 1000 + i;
EndFor
Spline(1) = lower[];
Spline(2) = upper[];
Line(3) = {1, 2}; Line(4) = {2, 100 + np}; Line(5) = {100 + np, 1000 + np};
Line(6) = {1000 + np, 3}; Line(7) = {3, 4}; Line(8) = {4, 1000};
Line(9) = {1000, 100}; Line(10) = {100, 1};
Curve Loop(1) = {3, 4, -1, 10}; Plane Surface(1) = {1};
Curve Loop(2) = {1, 5, -2, 9}; Plane Surface(2) = {2};
Curve Loop(3) = {2, 6, 7, 8}; Plane Surface(3) = {3};
Transfinite Curve{1, 2} = np + 1;
Transfinite Curve{5, 9} = l + 1;
Transfinite Surface{2};
Physical Surface("lower") = {1};
Physical Surface("medium") = {2};
Physical Surface("upper") = {3};
Physical Curve("bottom") = {3};
Physical Curve("top") = {7};
Physical Curve("left") = {10, 9, 8};
Physical Curve("right") = {4, 5, 6};
