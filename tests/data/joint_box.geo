// Box 0.1 x 0.1 x 0.1 m of two layers, regions "lower" (z < 0.05) and "upper", with their common face
// z = 0.05 named "joint" (Physical Surface). Node sets: bottom (z = 0), top (z = 0.1).
// Read by the tests (read_gmsh meshes it on the fly).
lc = 0.025;
Point(1) = {0, 0, 0, lc};
Point(2) = {0.1, 0, 0, lc};
Point(3) = {0.1, 0.1, 0, lc};
Point(4) = {0, 0.1, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
a[] = Extrude {0, 0, 0.05} { Surface{1}; };
b[] = Extrude {0, 0, 0.05} { Surface{a[0]}; };
Physical Volume("lower") = {a[1]};
Physical Volume("upper") = {b[1]};
Physical Surface("bottom") = {1};
Physical Surface("top") = {b[0]};
Physical Surface("joint") = {a[0]};
