// Unit square [0,1]^2, unstructured triangles.
// Mesh size: gmsh -2 square.geo -setnumber h 0.1 -format msh41 -o square.msh
DefineConstant[ h = {0.25, Name "Mesh size h"} ];

Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0, 1, 0, h};

Line(1) = {1, 2}; // bottom  y = 0
Line(2) = {2, 3}; // right   x = 1
Line(3) = {3, 4}; // top     y = 1
Line(4) = {4, 1}; // left    x = 0

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("left") = {4};
Physical Surface("body") = {1};
