// Rock slope with a weathered upper wedge (after Chang et al. 2014, section 4.1, Figure 18).
// A 20 m high slope face at 60 degrees; a weathered wedge bounded below by a plane at 35 degrees
// that daylights on the face 4 m above the toe, so the wedge is free to slide out over the face.
// The wedge carries interfaces (fracturable), the intact rock below does not.
// Lengths in m; element size h.
If (!Exists(h))
  h = 4.0;  // the coarsest; the case sets the size it wants (mesh.element_size, an upper bound)
EndIf
H = 20; toe = 20; hd = 4; face = 60 * Pi / 180; weak = 35 * Pi / 180; W = 80; B = 10;
xf = toe + H / Tan(face);          // crest of the slope face
xd = toe + hd / Tan(face);         // where the weak plane daylights on the face
xw = xd + (H - hd) / Tan(weak);    // where the weak plane meets the top surface
Point(1) = {0, -B, 0, h};
Point(2) = {W, -B, 0, h};
Point(3) = {W, H, 0, h};
Point(4) = {xw, H, 0, h};
Point(5) = {xf, H, 0, h};
Point(6) = {xd, hd, 0, h};
Point(7) = {toe, 0, 0, h};
Point(8) = {0, 0, 0, h};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right side
Line(3) = {3, 4};   // top of the intact rock
Line(4) = {4, 6};   // weak plane (base of the wedge)
Line(5) = {6, 7};   // lower slope face (intact)
Line(6) = {7, 8};   // ground in front of the toe
Line(7) = {8, 1};   // left side
Line(8) = {4, 5};   // top of the wedge
Line(9) = {5, 6};   // upper slope face (wedge)
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7};
Plane Surface(1) = {1};
Curve Loop(2) = {8, 9, -4};
Plane Surface(2) = {2};
Physical Surface("intact") = {1};
Physical Surface("weathered") = {2};
Physical Curve("bottom") = {1};
Physical Curve("sides") = {2, 7};
Physical Curve("crest") = {8};
Physical Point("wedge_top") = {5};
Mesh.Algorithm = 5;
