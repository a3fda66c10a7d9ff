// The box [-1,1] x [-1,1] x [0,0.5] of tests/obstacle_shapes.rs: tetrahedra of size h near the
// centre of the top face (within 0.3 of (0, 0, 0.5)), growing to 0.3 at 0.8 from it.
// gmsh -3 indent_box.geo -setnumber h 0.05 -format msh41 -o indent_box.msh
// Groups: "top" (z = 0.5), "bottom" (z = 0), "sides", "body".
SetFactory("OpenCASCADE");
DefineConstant[ h = {0.05, Name "Mesh size at the top centre"} ];

Box(1) = {-1, -1, 0, 2, 2, 0.5};
Point(100) = {0, 0, 0.5};
Field[1] = Distance;
Field[1].PointsList = {100};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h;
Field[2].SizeMax = 0.3;
Field[2].DistMin = 0.3;
Field[2].DistMax = 0.8;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;

eps = 1e-6;
bottom() = Surface In BoundingBox{-1 - eps, -1 - eps, -eps, 1 + eps, 1 + eps, eps};
top() = Surface In BoundingBox{-1 - eps, -1 - eps, 0.5 - eps, 1 + eps, 1 + eps, 0.5 + eps};
sides() = Boundary{ Volume{1}; };
sides() -= bottom();
sides() -= top();
Physical Surface("bottom") = {bottom()};
Physical Surface("top") = {top()};
Physical Surface("sides") = {sides()};
Physical Volume("body") = {1};
