// Two boxes meshed independently (tests/body_pairs.rs): lower [0,1]^2x[0,1] with mesh size
// hl, upper [0,1]^2x[1,2] with mesh size hu (gmsh -setnumber hl .. -setnumber hu ..). Each box
// has its own points, lines and faces: the face z = 1 is meshed twice, differently.
If (!Exists(hl))
  hl = 1/4;
EndIf
If (!Exists(hu))
  hu = 1/3;
EndIf
Point(1) = {0,0,0,hl};
Point(2) = {1,0,0,hl};
Point(3) = {1,1,0,hl};
Point(4) = {0,1,0,hl};
Point(5) = {0,0,1,hl};
Point(6) = {1,0,1,hl};
Point(7) = {1,1,1,hl};
Point(8) = {0,1,1,hl};
Line(1) = {1,2};
Line(2) = {2,3};
Line(3) = {3,4};
Line(4) = {4,1};
Line(5) = {5,6};
Line(6) = {6,7};
Line(7) = {7,8};
Line(8) = {8,5};
Line(9) = {1,5};
Line(10) = {2,6};
Line(11) = {3,7};
Line(12) = {4,8};
Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};
Curve Loop(2) = {5,6,7,8}; Plane Surface(2) = {2};
Curve Loop(3) = {1,10,-5,-9}; Plane Surface(3) = {3};
Curve Loop(4) = {2,11,-6,-10}; Plane Surface(4) = {4};
Curve Loop(5) = {3,12,-7,-11}; Plane Surface(5) = {5};
Curve Loop(6) = {4,9,-8,-12}; Plane Surface(6) = {6};
Surface Loop(1) = {1,2,3,4,5,6}; Volume(1) = {1};
Point(101) = {0,0,1,hu};
Point(102) = {1,0,1,hu};
Point(103) = {1,1,1,hu};
Point(104) = {0,1,1,hu};
Point(105) = {0,0,2,hu};
Point(106) = {1,0,2,hu};
Point(107) = {1,1,2,hu};
Point(108) = {0,1,2,hu};
Line(101) = {101,102};
Line(102) = {102,103};
Line(103) = {103,104};
Line(104) = {104,101};
Line(105) = {105,106};
Line(106) = {106,107};
Line(107) = {107,108};
Line(108) = {108,105};
Line(109) = {101,105};
Line(110) = {102,106};
Line(111) = {103,107};
Line(112) = {104,108};
Curve Loop(101) = {101,102,103,104}; Plane Surface(101) = {101};
Curve Loop(102) = {105,106,107,108}; Plane Surface(102) = {102};
Curve Loop(103) = {101,110,-105,-109}; Plane Surface(103) = {103};
Curve Loop(104) = {102,111,-106,-110}; Plane Surface(104) = {104};
Curve Loop(105) = {103,112,-107,-111}; Plane Surface(105) = {105};
Curve Loop(106) = {104,109,-108,-112}; Plane Surface(106) = {106};
Surface Loop(101) = {101,102,103,104,105,106}; Volume(101) = {101};
Physical Volume("lower") = {1};
Physical Volume("upper") = {101};
Physical Surface("bottom") = {1};
Physical Surface("lower_top") = {2};
Physical Surface("upper_bottom") = {101};
Physical Surface("top") = {102};
Physical Surface("x0") = {6, 106};
Physical Surface("y0") = {3, 103};
