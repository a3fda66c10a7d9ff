// block3d: the box [-1,1] x [-1,1] x [0,0.5], unstructured tetrahedra of size h (default 0.2).
// Groups: "bottom" (z = 0, contact), "top" (z = 0.5, load), "sides" (x = +-1, y = +-1), "body".
// gmsh -3 block3d.geo -format msh41 -bin -o block3d.msh   (or scripts/mesh blocks)
SetFactory("OpenCASCADE");
If (!Exists(h)) h = 0.2; EndIf
Box(1) = {-1, -1, 0, 2, 2, 0.5};
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;
Mesh.MeshSizeFromCurvature = 0;
eps = 1e-6;
bottom() = Surface In BoundingBox{-1 - eps, -1 - eps, -eps, 1 + eps, 1 + eps, eps};
top() = Surface In BoundingBox{-1 - eps, -1 - eps, 0.5 - eps, 1 + eps, 1 + eps, 0.5 + eps};
all() = Boundary{ Volume{1}; };
sides() = all();
sides() -= bottom();
sides() -= top();
Physical Surface("bottom") = {bottom()};
Physical Surface("top") = {top()};
Physical Surface("sides") = {sides()};
Physical Volume("body") = {1};
