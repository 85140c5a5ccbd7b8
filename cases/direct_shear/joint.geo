// Direct shear specimen: a square block 0.1 x 0.1 m of two regions, "lower" (y < 0.05) and
// "upper", with the joint between them (Physical Curve "joint", the line y = 0.05 across the whole
// width) and the node sets "bottom" and "top". Meshed by Gmsh when the case is run (lc: the
// element size).
lc = 0.01;
Point(1) = {0, 0, 0, lc};
Point(2) = {0.1, 0, 0, lc};
Point(3) = {0.1, 0.05, 0, lc};
Point(4) = {0.1, 0.1, 0, lc};
Point(5) = {0, 0.1, 0, lc};
Point(6) = {0, 0.05, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Line(7) = {6, 3};
Curve Loop(1) = {1, 2, -7, 6};  // counter-clockwise: triangles come out positively oriented
Plane Surface(1) = {1};
Curve Loop(2) = {7, 3, 4, 5};
Plane Surface(2) = {2};
Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("joint") = {7};
Physical Curve("bottom") = {1};
Physical Curve("top") = {4};
