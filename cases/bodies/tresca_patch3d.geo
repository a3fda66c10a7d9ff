// Two boxes meshed independently for the friction patch test between bodies
// (tests/body_tresca.rs): lower [0,1]^2x[0,1] with mesh size hl, upper [0,1]^2x[1,2] with mesh
// size hu (gmsh -setnumber hl .. -setnumber hu ..). Each box has its own points, lines and
// faces (the face z = 1 is meshed twice, differently), every face a group of its own: a
// uniform shear needs tractions on the sides of both boxes.
If (!Exists(hl))
  hl = 0.15;
EndIf
If (!Exists(hu))
  hu = 0.45;
EndIf
// box b (0 lower, 1 upper) from z = b to z = b + 1: points 100 b + 1..8, lines 100 b + 1..12,
// faces 100 b + 1..6 (z low, z high, y = 0, x = 1, y = 1, x = 0)
For b In {0:1}
  h = (b == 0) ? hl : hu;
  o = 100 * b;
  Point(o + 1) = {0,0,b,h}; Point(o + 2) = {1,0,b,h}; Point(o + 3) = {1,1,b,h}; Point(o + 4) = {0,1,b,h};
  Point(o + 5) = {0,0,b+1,h}; Point(o + 6) = {1,0,b+1,h}; Point(o + 7) = {1,1,b+1,h}; Point(o + 8) = {0,1,b+1,h};
  Line(o + 1) = {o + 1, o + 2}; Line(o + 2) = {o + 2, o + 3}; Line(o + 3) = {o + 3, o + 4}; Line(o + 4) = {o + 4, o + 1};
  Line(o + 5) = {o + 5, o + 6}; Line(o + 6) = {o + 6, o + 7}; Line(o + 7) = {o + 7, o + 8}; Line(o + 8) = {o + 8, o + 5};
  Line(o + 9) = {o + 1, o + 5}; Line(o + 10) = {o + 2, o + 6}; Line(o + 11) = {o + 3, o + 7}; Line(o + 12) = {o + 4, o + 8};
  Curve Loop(o + 1) = {o + 1, o + 2, o + 3, o + 4}; Plane Surface(o + 1) = {o + 1};
  Curve Loop(o + 2) = {o + 5, o + 6, o + 7, o + 8}; Plane Surface(o + 2) = {o + 2};
  Curve Loop(o + 3) = {o + 1, o + 10, -(o + 5), -(o + 9)}; Plane Surface(o + 3) = {o + 3};
  Curve Loop(o + 4) = {o + 2, o + 11, -(o + 6), -(o + 10)}; Plane Surface(o + 4) = {o + 4};
  Curve Loop(o + 5) = {o + 3, o + 12, -(o + 7), -(o + 11)}; Plane Surface(o + 5) = {o + 5};
  Curve Loop(o + 6) = {o + 4, o + 9, -(o + 8), -(o + 12)}; Plane Surface(o + 6) = {o + 6};
  Surface Loop(o + 1) = {o + 1, o + 2, o + 3, o + 4, o + 5, o + 6}; Volume(o + 1) = {o + 1};
EndFor
Physical Volume("lower") = {1};
Physical Volume("upper") = {101};
Physical Surface("bottom") = {1};
Physical Surface("lower_top") = {2};
Physical Surface("lower_y0") = {3};
Physical Surface("lower_x1") = {4};
Physical Surface("lower_y1") = {5};
Physical Surface("lower_x0") = {6};
Physical Surface("upper_bottom") = {101};
Physical Surface("top") = {102};
Physical Surface("upper_y0") = {103};
Physical Surface("upper_x1") = {104};
Physical Surface("upper_y1") = {105};
Physical Surface("upper_x0") = {106};
