// 2 x 1 rectangle split at x = 1 into two physical surfaces: "rock" (left) and "weak" (right).
// Regenerate the test meshes with:
//   gmsh two_regions.geo -2 -format msh22 -o two_regions_v22.msh
//   gmsh two_regions.geo -2 -format msh22 -bin -o two_regions_v22_bin.msh
//   gmsh two_regions.geo -2 -format msh41 -o two_regions_v41.msh
//   gmsh two_regions.geo -2 -format msh41 -bin -o two_regions_v41_bin.msh
lc = 0.3;
Point(1) = {0, 0, 0, lc};
Point(2) = {1, 0, 0, lc};
Point(3) = {2, 0, 0, lc};
Point(4) = {2, 1, 0, lc};
Point(5) = {1, 1, 0, lc};
Point(6) = {0, 1, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 6};
Line(6) = {6, 1};
Line(7) = {2, 5};
Curve Loop(1) = {1, 7, 5, 6};   // counter-clockwise: triangles come out positively oriented
Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 4, -7};
Plane Surface(2) = {2};
Physical Surface("rock") = {1};
Physical Surface("weak") = {2};
Physical Curve("left") = {6};
Physical Curve("right") = {3};
Physical Curve("bottom") = {1, 2};
Physical Curve("top") = {4, 5};
Physical Curve(17) = {7};       // unnamed: becomes node set "group_17"
Physical Point("origin") = {1};
