// A thin strip [0, 4] x [0, 0.1], structured: 3 601 nodes on its bottom (the contact group), 8
// layers. Mesh: gmsh -2 strip.geo -format msh41 -o strip.msh
Point(1) = {0, 0, 0};
Point(2) = {4, 0, 0};
Point(3) = {4, 0.1, 0};
Point(4) = {0, 0.1, 0};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Transfinite Curve {1, 3} = 3601;
Transfinite Curve {2, 4} = 9;
Transfinite Surface {1};
Physical Curve("bottom") = {1};
Physical Curve("top") = {3};
Physical Surface("body") = {1};
