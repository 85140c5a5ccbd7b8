// Square block 0.1 x 0.1 m, regions "lower" (y < 0.05) and "upper", with a named joint: the horizontal line
// y = 0.05 across the whole width (Physical Curve "joint"), and a crack "crack" from the left
// side to the centre (x = 0 .. 0.05) at y = 0.025 that ends inside the block. Node sets: bottom, top.
// Read by the tests (read_gmsh meshes it on the fly).
lc = 0.01;
Point(1) = {0, 0, 0, lc};
Point(2) = {0.1, 0, 0, lc};
Point(3) = {0.1, 0.05, 0, lc};
Point(4) = {0.1, 0.1, 0, lc};
Point(5) = {0, 0.1, 0, lc};
Point(6) = {0, 0.05, 0, lc};
Point(7) = {0, 0.025, 0, lc};
Point(8) = {0.05, 0.025, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 7};
Line(7) = {7, 1};
Line(8) = {6, 3};
Line(9) = {7, 8};
Curve Loop(1) = {1, 2, -8, 6, 7};  // counter-clockwise: triangles come out positively oriented
Plane Surface(1) = {1};
Curve Loop(2) = {8, 3, 4, 5};
Plane Surface(2) = {2};
Line {9} In Surface {1};
Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("joint") = {8};
Physical Curve("crack") = {9};
Physical Curve("bottom") = {1};
Physical Curve("top") = {4};
