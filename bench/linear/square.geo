// Benchmark geometry, 2D: the unit square, clamped on the left, pressed on the top.
// Unstructured linear triangles (Frontal-Delaunay); h sets the mesh size:
//   gmsh -2 square.geo -setnumber h 0.01 -format msh41 -bin -o square.msh
// Nodes ~ 1.15 / h^2.
If (!Exists(h)) h = 0.05; EndIf
Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0, 1, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("load") = {3};
Physical Curve("clamp") = {4};
Physical Surface("body") = {1};
