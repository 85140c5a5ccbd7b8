// Single-edge-notched beam after Galvez et al. (1998), 2D (plane stress, thickness in the case).
// Length 675 mm, depth 150 mm, notch 75 mm deep and 5 mm wide at mid-span of the bottom edge.
// Bottom supports at x = -300 and +300 mm from mid-span (20 mm pads), load pad on the top edge
// centred 150 mm right of mid-span (20 mm). Lengths in m. Element size h (change with -setnumber
// or by editing; the case's mesh.file points here and Gmsh meshes it when the case is read).
If (!Exists(h))
  h = 0.010;
EndIf
L = 0.675; H = 0.150; a = 0.075; w = 0.005; s = 0.300; p = 0.010; xl = 0.150;
hn = h / 2;  // finer near the notch tip
Point(1) = {-L/2, 0, 0, h};
Point(2) = {-s - p, 0, 0, h};
Point(3) = {-s + p, 0, 0, h};
Point(4) = {-w/2, 0, 0, hn};
Point(5) = {-w/2, a, 0, hn};
Point(6) = {w/2, a, 0, hn};
Point(7) = {w/2, 0, 0, hn};
Point(8) = {s - p, 0, 0, h};
Point(9) = {s + p, 0, 0, h};
Point(10) = {L/2, 0, 0, h};
Point(11) = {L/2, H, 0, h};
Point(12) = {xl + p, H, 0, h};
Point(13) = {xl - p, H, 0, h};
Point(14) = {-L/2, H, 0, h};
For i In {1:13}
  Line(i) = {i, i + 1};
EndFor
Line(14) = {14, 1};
Curve Loop(1) = {1:14};
Plane Surface(1) = {1};
Physical Surface("body") = {1};
Physical Curve("support_left") = {2};
Physical Curve("support_right") = {8};
Physical Curve("load") = {12};
Physical Point("mouth_left") = {4};
Physical Point("mouth_right") = {7};
Mesh.Algorithm = 6;
