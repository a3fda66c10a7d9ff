// A block [-1,1] x [0,1] of two materials: a substrate ("substrate", y < 0.9) under a coating
// ("coating", 0.9 < y < 1); one conforming interface at y = 0.9. Fine (h = hc) near the top
// centre, where examples/coated_block.toml indents it.
// gmsh -2 coated2d.geo -format msh41 -o coated2d.msh (scripts/mesh blocks)
DefineConstant[ hc = {0.02, Name "Mesh size at the top centre"} ];
DefineConstant[ h = {0.15, Name "Mesh size elsewhere"} ];

Point(1) = {-1, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 0.9, 0, h};
Point(4) = {-1, 0.9, 0, h};
Point(5) = {1, 1, 0, h};
Point(6) = {-1, 1, 0, h};
Point(7) = {-0.3, 1, 0, hc};
Point(8) = {0.3, 1, 0, hc};
Point(9) = {-0.3, 0.9, 0, hc};
Point(10) = {0.3, 0.9, 0, hc};

Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right side of the substrate
Line(3) = {3, 10};  // interface
Line(4) = {10, 9};
Line(5) = {9, 4};
Line(6) = {4, 1};   // left side of the substrate
Line(7) = {3, 5};   // right side of the coating
Line(8) = {5, 8};   // top
Line(9) = {8, 7};
Line(10) = {7, 6};
Line(11) = {6, 4};  // left side of the coating

Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};
Curve Loop(2) = {-3, 7, 8, 9, 10, 11, -5, -4};
Plane Surface(2) = {2};

Physical Curve("bottom") = {1};
Physical Curve("top") = {8, 9, 10};
Physical Curve("sides") = {2, 6, 7, 11};
Physical Surface("substrate") = {1};
Physical Surface("coating") = {2};
