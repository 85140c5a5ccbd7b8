// Rock slope with a weathered upper wedge (after Chang et al. 2014, section 4.1, Figure 18).
// A 20 m high slope face at 60 degrees; a weathered wedge bounded below by a plane at 35 degrees
// through the toe. The wedge carries interfaces (fracturable), the intact rock below does not.
// Lengths in m; element size h.
If (!Exists(h))
  h = 1.0;
EndIf
H = 20; toe = 20; face = 60 * Pi / 180; weak = 35 * Pi / 180; W = 80; B = 10;
xf = toe + H / Tan(face);   // crest of the slope face
xw = toe + H / Tan(weak);   // where the weak plane meets the top surface
Point(1) = {0, -B, 0, h};
Point(2) = {W, -B, 0, h};
Point(3) = {W, H, 0, h};
Point(4) = {xw, H, 0, h};
Point(5) = {xf, H, 0, h};
Point(6) = {toe, 0, 0, h};
Point(7) = {0, 0, 0, h};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right
Line(3) = {3, 4};   // top of the intact rock
Line(4) = {4, 6};   // weak plane (wedge base)
Line(5) = {6, 7};   // ground in front of the toe
Line(6) = {7, 1};   // left
Line(7) = {4, 5};   // top of the wedge
Line(8) = {5, 6};   // slope face
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {7, 8, -4};
Plane Surface(2) = {2};
Physical Surface("intact") = {1};
Physical Surface("weathered") = {2};
Physical Curve("bottom") = {1};
Physical Curve("sides") = {2, 6};
Physical Curve("crest") = {7};
Physical Point("wedge_top") = {5};
Mesh.Algorithm = 5;
