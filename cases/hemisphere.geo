// hemisphere: the lower cap of the unit ball centred at (0, 0, 1), cut by the plane z = H
// (default H = 1: the lower hemisphere); its lowest point touches the plane z = 0 at the origin.
// Mesh size hc within r0 of the lowest point, growing linearly to hf at distance r1.
// Groups: "contact" (the spherical surface), "top" (the flat face z = H), "body".
// gmsh -3 hemisphere.geo -setnumber hc 0.0125 -format msh41 -bin -o hemisphere.msh
// (hc = 0.0125: 10 248 nodes; 0.015: 6 875; 0.01: 17 318)
SetFactory("OpenCASCADE");
If (!Exists(H)) H = 1.0; EndIf
If (!Exists(hc)) hc = 0.0125; EndIf
If (!Exists(hf)) hf = 0.15; EndIf
If (!Exists(r0)) r0 = 0.2; EndIf
If (!Exists(r1)) r1 = 0.7; EndIf
Sphere(1) = {0, 0, 1, 1};
Box(2) = {-2, -2, 0 - 1, 4, 4, H + 1};
BooleanIntersection(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
eps = 1e-6;
top() = Surface In BoundingBox{-2, -2, H - eps, 2, 2, H + eps};
all() = Boundary{ Volume{3}; };
curved() = all();
curved() -= top();
Physical Surface("contact") = {curved()};
Physical Surface("top") = {top()};
Physical Volume("body") = {3};
Point(100) = {0, 0, 0};
Field[1] = Distance;
Field[1].PointsList = {100};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = hc;
Field[2].SizeMax = hf;
Field[2].DistMin = r0;
Field[2].DistMax = r1;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
