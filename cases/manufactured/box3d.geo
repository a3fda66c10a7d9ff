// box3d: the box [-1,1] x [-1,1] x [0,1], unstructured tetrahedra of size h (default 0.25), the
// coarse mesh of the 3D manufactured contact solution (contact3d.toml; finer levels by
// mesh.refine). Groups: "bottom" (z = 0, contact), "top" (z = 1), "sides" (x = +-1, y = +-1),
// "body".
// gmsh -3 box3d.geo -format msh41 -bin -o box3d.msh
SetFactory("OpenCASCADE");
If (!Exists(h)) h = 0.25; EndIf
Box(1) = {-1, -1, 0, 2, 2, 1};
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;
Mesh.MeshSizeFromCurvature = 0;
eps = 1e-6;
bottom() = Surface In BoundingBox{-1 - eps, -1 - eps, -eps, 1 + eps, 1 + eps, eps};
top() = Surface In BoundingBox{-1 - eps, -1 - eps, 1 - eps, 1 + eps, 1 + eps, 1 + eps};
all() = Boundary{ Volume{1}; };
sides() = all();
sides() -= bottom();
sides() -= top();
Physical Surface("bottom") = {bottom()};
Physical Surface("top") = {top()};
Physical Surface("sides") = {sides()};
Physical Volume("body") = {1};
