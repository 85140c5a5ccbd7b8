// Unit cube of tetrahedra, meshed on the fly by the tests (read_gmsh of a .geo file).
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Mesh.CharacteristicLengthMax = 0.4;
Physical Volume("cube") = {1};
Physical Surface("zmin") = {5};
Physical Surface("zmax") = {6};
