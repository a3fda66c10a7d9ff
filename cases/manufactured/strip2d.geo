// strip2d: the rectangle [-1,1] x [0,1], unstructured triangles of size h (default 0.125), the
// coarse mesh of the manufactured contact solution (contact2d.toml; finer levels by
// mesh.refine). Groups: "bottom" (y = 0, contact), "top", "left", "right", "body".
// gmsh -2 strip2d.geo -format msh41 -bin -o strip2d.msh
If (!Exists(h)) h = 0.125; EndIf
Point(1) = {-1, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {-1, 1, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Mesh.MeshSizeFromCurvature = 0;
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Surface("body") = {1};
