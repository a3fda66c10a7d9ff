// A bar [0,2]x[0,1]x[0,1] of two materials in series: "soft" = x < 1, "hard" = x > 1 (one
// shared, conforming interface at x = 1), unstructured tetrahedra.
// gmsh -3 bimaterial_bar3d.geo -setnumber h 0.5 -format msh41 -o bimaterial_bar3d.msh
SetFactory("OpenCASCADE");
DefineConstant[ h = {0.5, Name "Mesh size h"} ];

Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
BooleanFragments{ Volume{1, 2}; Delete; }{}
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;

eps = 1e-6;
soft() = Volume In BoundingBox{-eps, -eps, -eps, 1+eps, 1+eps, 1+eps};
hard() = Volume In BoundingBox{1-eps, -eps, -eps, 2+eps, 1+eps, 1+eps};
start() = Surface In BoundingBox{-eps, -eps, -eps, eps, 1+eps, 1+eps};
end() = Surface In BoundingBox{2-eps, -eps, -eps, 2+eps, 1+eps, 1+eps};
bottom() = Surface In BoundingBox{-eps, -eps, -eps, 2+eps, eps, 1+eps};
front() = Surface In BoundingBox{-eps, -eps, -eps, 2+eps, 1+eps, eps};

Physical Surface("start") = {start()};   // x = 0
Physical Surface("end") = {end()};       // x = 2
Physical Surface("bottom") = {bottom()}; // y = 0
Physical Surface("front") = {front()};   // z = 0
Physical Volume("soft") = {soft()};
Physical Volume("hard") = {hard()};
