// A bar [0,2]x[0,1] of two materials in series: "soft" = [0,1]x[0,1], "hard" = [1,2]x[0,1]
// (one shared, conforming interface at x = 1), unstructured triangles.
// gmsh -2 bimaterial_bar.geo -setnumber h 0.2 -format msh41 -o bimaterial_bar.msh
DefineConstant[ h = {0.2, Name "Mesh size h"} ];

Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {2, 0, 0, h};
Point(4) = {2, 1, 0, h};
Point(5) = {1, 1, 0, h};
Point(6) = {0, 1, 0, h};

Line(1) = {1, 2}; // bottom of soft  y = 0
Line(2) = {2, 3}; // bottom of hard  y = 0
Line(3) = {3, 4}; // end             x = 2
Line(4) = {4, 5}; // top of hard     y = 1
Line(5) = {5, 6}; // top of soft     y = 1
Line(6) = {6, 1}; // start           x = 0
Line(7) = {2, 5}; // interface       x = 1

Curve Loop(1) = {1, 7, 5, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {2, 3, 4, -7};
Plane Surface(2) = {2};

Physical Curve("bottom") = {1, 2};
Physical Curve("start") = {6};
Physical Curve("end") = {3};
Physical Curve("top") = {4, 5};
Physical Surface("soft") = {1};
Physical Surface("hard") = {2};
Physical Surface("bar") = {1, 2}; // every cell: a second material for all of them is refused
