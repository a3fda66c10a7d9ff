// A strip [0,4] x [0,1] of four unit squares that share their sides (one body): the
// lines x = 1 and x = 3 lie inside it (tests/cli_reject.rs: load and contact groups of
// interior facets, far apart so that the ranks of a distributed mesh hold different ones).
// gmsh -2 strip_cuts.geo -setnumber h 0.1 -format msh41 -o strip_cuts.msh
DefineConstant[ h = {0.1, Name "Mesh size h"} ];

For i In {0:4}
  Point(1 + 2 * i) = {i, 0, 0, h};
  Point(2 + 2 * i) = {i, 1, 0, h};
EndFor
For i In {0:3}
  Line(1 + i) = {1 + 2 * i, 3 + 2 * i};
  Line(11 + i) = {2 + 2 * i, 4 + 2 * i};
EndFor
For i In {0:4}
  Line(21 + i) = {1 + 2 * i, 2 + 2 * i};
EndFor
For i In {0:3}
  Curve Loop(1 + i) = {1 + i, 22 + i, -(11 + i), -(21 + i)};
  Plane Surface(1 + i) = {1 + i};
EndFor
Physical Surface("body") = {1, 2, 3, 4};
Physical Curve("bottom") = {1, 2, 3, 4};
Physical Curve("top") = {11, 12, 13, 14};
Physical Curve("left") = {21};
Physical Curve("right") = {25};
Physical Curve("cut1") = {22};
Physical Curve("cut3") = {24};
