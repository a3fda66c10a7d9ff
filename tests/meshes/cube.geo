// Unit cube [0,1]^3, unstructured tetrahedra.
// Mesh size: gmsh -3 cube.geo -setnumber h 0.1 -format msh41 -o cube.msh
SetFactory("OpenCASCADE");
DefineConstant[ h = {0.5, Name "Mesh size h"} ];

Box(1) = {0, 0, 0, 1, 1, 1};
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;

// Identify the six faces by their position (robust to the OCC face numbering).
eps = 1e-6;
left()   = Surface In BoundingBox{-eps, -eps, -eps,  eps, 1+eps, 1+eps};
right()  = Surface In BoundingBox{1-eps, -eps, -eps, 1+eps, 1+eps, 1+eps};
bottom() = Surface In BoundingBox{-eps, -eps, -eps, 1+eps,  eps, 1+eps};
top()    = Surface In BoundingBox{-eps, 1-eps, -eps, 1+eps, 1+eps, 1+eps};
front()  = Surface In BoundingBox{-eps, -eps, -eps, 1+eps, 1+eps,  eps};
back()   = Surface In BoundingBox{-eps, -eps, 1-eps, 1+eps, 1+eps, 1+eps};

Physical Surface("left") = {left()};     // x = 0
Physical Surface("right") = {right()};   // x = 1
Physical Surface("bottom") = {bottom()}; // y = 0
Physical Surface("top") = {top()};       // y = 1
Physical Surface("front") = {front()};   // z = 0
Physical Surface("back") = {back()};     // z = 1
Physical Volume("body") = {1};
