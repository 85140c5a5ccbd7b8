// Single-edge-notched beam after Galvez et al. (1998), 2D (plane stress, thickness in the case).
// Length 675 mm, depth 150 mm, notch 75 mm deep and 5 mm wide at mid-span of the bottom edge.
// Steel bearing blocks 20 mm wide and 10 mm high: two under the bottom edge centred at x = -300
// and +300 mm from mid-span (the supports), one on the top edge centred 150 mm right of
// mid-span (the load). Rigid platens in the case press on the blocks only, so the beam is
// loaded at points and free to rotate there. Lengths in m.
// Element sizes: hf in the band -40 mm < x < 190 mm where the crack runs (from the notch to the
// load block) and in the blocks, h elsewhere; the case's mesh.element_size is an upper bound.
If (!Exists(h))
  h = 0.020;
EndIf
If (!Exists(hf))
  hf = 0.010;
EndIf
L = 0.675; H = 0.150; a = 0.075; w = 0.005; s = 0.300; p = 0.010; xl = 0.150; hb = 0.010;
hp = hf;  // the blocks
// beam outline, counter-clockwise from the lower left corner
Point(1) = {-L/2, 0, 0, h};
Point(2) = {-s - p, 0, 0, hp};
Point(3) = {-s + p, 0, 0, hp};
Point(4) = {-w/2, 0, 0, hf};
Point(5) = {-w/2, a, 0, hf};
Point(6) = {w/2, a, 0, hf};
Point(7) = {w/2, 0, 0, hf};
Point(8) = {s - p, 0, 0, hp};
Point(9) = {s + p, 0, 0, hp};
Point(10) = {L/2, 0, 0, h};
Point(11) = {L/2, H, 0, h};
Point(12) = {xl + p, H, 0, hp};
Point(13) = {xl - p, H, 0, hp};
Point(14) = {-L/2, H, 0, h};
For i In {1:13}
  Line(i) = {i, i + 1};
EndFor
Line(14) = {14, 1};
Curve Loop(1) = {1:14};
Plane Surface(1) = {1};
// blocks: left support (lines 2 shared), right support (line 8 shared), load (line 12 shared)
Point(21) = {-s - p, -hb, 0, hp};
Point(22) = {-s, -hb, 0, hp};  // the left support block's bottom centre: pinned in x ("pin")
Point(23) = {-s + p, -hb, 0, hp};
Line(21) = {2, 21};
Line(22) = {21, 22};
Line(23) = {22, 23};
Line(24) = {23, 3};
Curve Loop(2) = {21, 22, 23, 24, -2};
Plane Surface(2) = {2};
Point(31) = {s - p, -hb, 0, hp};
Point(32) = {s + p, -hb, 0, hp};
Line(31) = {8, 31};
Line(32) = {31, 32};
Line(33) = {32, 9};
Curve Loop(3) = {31, 32, 33, -8};
Plane Surface(3) = {3};
Point(41) = {xl + p, H + hb, 0, hp};
Point(42) = {xl - p, H + hb, 0, hp};
Line(41) = {12, 41};
Line(42) = {41, 42};
Line(43) = {42, 13};
Curve Loop(4) = {41, 42, 43, -12};
Plane Surface(4) = {4};
Physical Surface("body") = {1};
Physical Surface("blocks") = {2, 3, 4};
Physical Point("pin") = {22};
Physical Point("mouth_left") = {4};
Physical Point("mouth_right") = {7};
Physical Point("load_point") = {13};  // the top edge under the load block's left edge
Field[1] = Box;
Field[1].VIn = hf;
Field[1].VOut = h;
Field[1].XMin = -0.040;
Field[1].XMax = 0.190;
Field[1].YMin = -1;
Field[1].YMax = 1;
Field[2] = Box;  // the support blocks and the beam just above them
Field[2].VIn = hf;
Field[2].VOut = h;
Field[2].XMin = -s - 2 * p;
Field[2].XMax = -s + 2 * p;
Field[2].YMin = -1;
Field[2].YMax = 2 * p;
Field[3] = Box;
Field[3].VIn = hf;
Field[3].VOut = h;
Field[3].XMin = s - 2 * p;
Field[3].XMax = s + 2 * p;
Field[3].YMin = -1;
Field[3].YMax = 2 * p;
Field[4] = Min;
Field[4].FieldsList = {1, 2, 3};
Background Field = 4;
Mesh.Algorithm = 6;
Mesh.MeshSizeExtendFromBoundary = 0;
