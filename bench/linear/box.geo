// Benchmark geometry, 3D: a 2 x 1 x 1 box clamped at x = 0, pressed on the top z = 1.
// Unstructured linear tetrahedra (HXT); h sets the mesh size:
//   gmsh -3 box.geo -setnumber h 0.05 -format msh41 -bin -o box.msh
If (!Exists(h)) h = 0.2; EndIf
SetFactory("Built-in");
Point(1) = {0, 0, 0, h};
Point(2) = {2, 0, 0, h};
Point(3) = {2, 1, 0, h};
Point(4) = {0, 1, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
out[] = Extrude {0, 0, 1} { Surface{1}; };
// out[0] = top (z = 1), out[1] = volume, out[2..5] = sides on lines 1..4
Physical Surface("bottom") = {1};
Physical Surface("load") = {out[0]};
Physical Surface("clamp") = {out[5]};
Physical Surface("sides") = {out[2], out[3], out[4]};
Physical Volume("body") = {out[1]};
Mesh.Algorithm = 6;
Mesh.Algorithm3D = 10;
