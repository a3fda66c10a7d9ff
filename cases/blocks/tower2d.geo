// Three blocks stacked and meshed independently (examples/stacked_blocks.toml,
// tests/body_pairs.rs): [0,1]x[0,1] with
// mesh size h1, [0,1]x[1,2] with h2, [0,1]x[2,3] with h3 (gmsh -setnumber h1 .. ).
If (!Exists(h1))
  h1 = 1/7;
EndIf
If (!Exists(h2))
  h2 = 1/3;
EndIf
If (!Exists(h3))
  h3 = 1/5;
EndIf
Point(1) = {0,0,0,h1}; Point(2) = {1,0,0,h1}; Point(3) = {1,1,0,h1}; Point(4) = {0,1,0,h1};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};
Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};
Point(11) = {0,1,0,h2}; Point(12) = {1,1,0,h2}; Point(13) = {1,2,0,h2}; Point(14) = {0,2,0,h2};
Line(11) = {11,12}; Line(12) = {12,13}; Line(13) = {13,14}; Line(14) = {14,11};
Curve Loop(11) = {11,12,13,14}; Plane Surface(11) = {11};
Point(21) = {0,2,0,h3}; Point(22) = {1,2,0,h3}; Point(23) = {1,3,0,h3}; Point(24) = {0,3,0,h3};
Line(21) = {21,22}; Line(22) = {22,23}; Line(23) = {23,24}; Line(24) = {24,21};
Curve Loop(21) = {21,22,23,24}; Plane Surface(21) = {21};
Physical Surface("lower") = {1};
Physical Surface("middle") = {11};
Physical Surface("upper") = {21};
Physical Curve("bottom") = {1};
Physical Curve("lower_top") = {3};
Physical Curve("middle_bottom") = {11};
Physical Curve("middle_top") = {13};
Physical Curve("upper_bottom") = {21};
Physical Curve("top") = {23};
Physical Curve("left") = {4, 14, 24};
