// indent2d: the block [-1,1] x [0,1], to be indented from above by a rigid circle.
// Unstructured triangles: size hf (default 0.01) within |x - (0,1)| < r0 (default 0.15),
// growing linearly (rate 0.3) to h (default 0.1) away from the top centre.
// Groups: "bottom" (y = 0, fixed), "top" (y = 1, contact), "left", "right", "body".
// gmsh -2 indent2d.geo -format msh41 -bin -o indent2d.msh   (or scripts/mesh blocks)
If (!Exists(h)) h = 0.1; EndIf
If (!Exists(hf)) hf = 0.01; EndIf
If (!Exists(r0)) r0 = 0.15; EndIf
Point(1) = {-1, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0, 1, 0, hf};      // top centre: first contact point, a mesh node
Point(5) = {-1, 1, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 5};
Line(5) = {5, 1};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Field[1] = Distance;
Field[1].PointsList = {4};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hf;
Field[2].SizeMax = h;
Field[2].DistMin = r0;
Field[2].DistMax = r0 + (h - hf) / 0.3;
Background Field = 2;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3, 4};
Physical Curve("left") = {5};
Physical Surface("body") = {1};
