// Two blocks meshed independently for the friction patch test between bodies
// (tests/body_tresca.rs): lower [0,1]x[0,1] with mesh size hl, upper [0,1]x[1,2] with mesh size
// hu (gmsh -setnumber hl .. -setnumber hu ..). Every side of each block is a group of its own:
// a uniform shear needs tractions on the sides of both blocks.
If (!Exists(hl))
  hl = 0.095;
EndIf
If (!Exists(hu))
  hu = 0.3;
EndIf
Point(1) = {0,0,0,hl}; Point(2) = {1,0,0,hl}; Point(3) = {1,1,0,hl}; Point(4) = {0,1,0,hl};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};
Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};
Point(11) = {0,1,0,hu}; Point(12) = {1,1,0,hu}; Point(13) = {1,2,0,hu}; Point(14) = {0,2,0,hu};
Line(11) = {11,12}; Line(12) = {12,13}; Line(13) = {13,14}; Line(14) = {14,11};
Curve Loop(11) = {11,12,13,14}; Plane Surface(11) = {11};
Physical Surface("lower") = {1};
Physical Surface("upper") = {11};
Physical Curve("bottom") = {1};
Physical Curve("lower_x1") = {2};
Physical Curve("lower_top") = {3};
Physical Curve("lower_x0") = {4};
Physical Curve("upper_bottom") = {11};
Physical Curve("upper_x1") = {12};
Physical Curve("top") = {13};
Physical Curve("upper_x0") = {14};
