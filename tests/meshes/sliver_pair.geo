// A block [0, 0.6 + 2 d] x [1, 1.3] (x from 0.3 - d) on a block [0, 1]^2 whose top has nodes at
// x = 0.3 and 0.7: with d = 1e-12 the upper block's bottom reaches a sliver of 1e-12 into the
// lower top's facets beside those nodes (tests/mortar_slivers.rs).
// gmsh -2 sliver_pair.geo -setnumber h 0.1 -setnumber d 1e-12 -format msh41 -o sliver_pair.msh
DefineConstant[ h = {0.1, Name "Mesh size h"}, d = {0, Name "Overhang d"} ];

Point(1) = {0, 0, 0, h};
Point(2) = {1, 0, 0, h};
Point(3) = {1, 1, 0, h};
Point(4) = {0.7, 1, 0, h};
Point(5) = {0.3, 1, 0, h};
Point(6) = {0, 1, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 5}; Line(5) = {5, 6};
Line(6) = {6, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};

Point(11) = {0.3 - d, 1, 0, 0.6 * h};
Point(12) = {0.7 + d, 1, 0, 0.6 * h};
Point(13) = {0.7 + d, 1.3, 0, 0.6 * h};
Point(14) = {0.3 - d, 1.3, 0, 0.6 * h};
Line(11) = {11, 12}; Line(12) = {12, 13}; Line(13) = {13, 14}; Line(14) = {14, 11};
Curve Loop(2) = {11, 12, 13, 14};
Plane Surface(2) = {2};

Physical Curve("lower_bottom") = {1};
Physical Curve("lower_top") = {3, 4, 5};
Physical Curve("upper_bottom") = {11};
Physical Curve("upper_top") = {13};
Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
