// Two separate unit squares, [0,1]^2 and [2,3]x[0,1]: a mesh of two bodies.
// gmsh -2 two_squares.geo -setnumber h 0.1 -format msh41 -o two_squares.msh
DefineConstant[ h = {0.1, Name "Mesh size h"} ];

Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0, 1, 0, h};
Point(5) = {2, 0, 0, h};
Point(6) = {3, 0, 0, h};
Point(7) = {3, 1, 0, h};
Point(8) = {2, 1, 0, h};

Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};

Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(2) = {2};

Physical Curve("bottom") = {1, 5};
Physical Curve("top") = {3, 7};
Physical Curve("left_a") = {4};
Physical Curve("left_b") = {8};
Physical Curve("bottom_a") = {1};
Physical Surface("body") = {1, 2};
