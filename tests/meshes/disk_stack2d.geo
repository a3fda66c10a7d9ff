// Two disks (R = 0.3) stacked on a block [-1,1] x [-0.5,0] (tests/body_pairs.rs): disk 1
// (centre (0, 0.3)) rests on the block, disk 2 (centre (0, 0.9)) on disk 1; three bodies
// meshed apart, each circle of eight arcs. Groups: block, disk1, disk2 (surfaces),
// block_top, block_bottom, d1_bottom (the quarter of disk 1 around its lowest point), d1_top
// (the quarter around its highest), d2_bottom. With -setnumber shared 1, d1_top is the three
// quarters above d1_bottom instead and shares d1_bottom's two end nodes.
If (!Exists(h))
  h = 0.04;
EndIf
If (!Exists(shared))
  shared = 0;
EndIf
Point(1) = {-1, -0.5, 0, 4 * h};
Point(2) = {1, -0.5, 0, 4 * h};
Point(3) = {1, 0, 0, h};
Point(4) = {-1, 0, 0, h};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};
// disk centre (0, 0.3); arc 10+i+1 from 45*i - 90 degrees on
Point(10) = {0, 0.3, 0, h};
Point(11) = {1.83697019872103e-17, 0, 0, h / 2};
Point(12) = {0.212132034355964, 0.0878679656440358, 0, h};
Point(13) = {0.3, 0.3, 0, h};
Point(14) = {0.212132034355964, 0.512132034355964, 0, h};
Point(15) = {1.83697019872103e-17, 0.6, 0, h / 2};
Point(16) = {-0.212132034355964, 0.512132034355964, 0, h};
Point(17) = {-0.3, 0.3, 0, h};
Point(18) = {-0.212132034355964, 0.0878679656440358, 0, h};
Circle(11) = {11, 10, 12};
Circle(12) = {12, 10, 13};
Circle(13) = {13, 10, 14};
Circle(14) = {14, 10, 15};
Circle(15) = {15, 10, 16};
Circle(16) = {16, 10, 17};
Circle(17) = {17, 10, 18};
Circle(18) = {18, 10, 11};
Curve Loop(10) = {11, 12, 13, 14, 15, 16, 17, 18};
Plane Surface(10) = {10};
// disk centre (0, 0.9); arc 30+i+1 from 45*i - 90 degrees on
Point(30) = {0, 0.9, 0, h};
Point(31) = {1.83697019872103e-17, 0.6, 0, h / 2};
Point(32) = {0.212132034355964, 0.687867965644036, 0, h};
Point(33) = {0.3, 0.9, 0, h};
Point(34) = {0.212132034355964, 1.11213203435596, 0, h};
Point(35) = {1.83697019872103e-17, 1.2, 0, h / 2};
Point(36) = {-0.212132034355964, 1.11213203435596, 0, h};
Point(37) = {-0.3, 0.9, 0, h};
Point(38) = {-0.212132034355964, 0.687867965644036, 0, h};
Circle(31) = {31, 30, 32};
Circle(32) = {32, 30, 33};
Circle(33) = {33, 30, 34};
Circle(34) = {34, 30, 35};
Circle(35) = {35, 30, 36};
Circle(36) = {36, 30, 37};
Circle(37) = {37, 30, 38};
Circle(38) = {38, 30, 31};
Curve Loop(30) = {31, 32, 33, 34, 35, 36, 37, 38};
Plane Surface(30) = {30};
Physical Surface("block") = {1};
Physical Surface("disk1") = {10};
Physical Surface("disk2") = {30};
Physical Curve("block_top") = {3};
Physical Curve("block_bottom") = {1};
Physical Curve("d1_bottom") = {11, 18};
If (shared == 0)
  Physical Curve("d1_top") = {14, 15};
Else
  Physical Curve("d1_top") = {12, 13, 14, 15, 16, 17};
EndIf
Physical Curve("d2_bottom") = {31, 38};
