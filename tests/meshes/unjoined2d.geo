// Two unit squares side by side, meshed apart: their shared side has two sets of nodes unless
// `joined` is 1 (Coherence makes the mesh conformal). tests/warnings.rs (unjoined_nodes).
If (!Exists(h))
  h = 0.1;
EndIf
If (!Exists(joined))
  joined = 0;
EndIf
Point(1) = {0, 0, 0, h}; Point(2) = {1, 0, 0, h}; Point(3) = {1, 1, 0, h}; Point(4) = {0, 1, 0, h};
Point(5) = {1, 0, 0, h}; Point(6) = {2, 0, 0, h}; Point(7) = {2, 1, 0, h}; Point(8) = {1, 1, 0, h};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Line(5) = {5, 6}; Line(6) = {6, 7}; Line(7) = {7, 8}; Line(8) = {8, 5};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Curve Loop(2) = {5, 6, 7, 8}; Plane Surface(2) = {2};
If (joined)
  Coherence;
EndIf
Physical Curve("bottom") = {1, 5};
Physical Curve("top") = {3, 7};
Physical Surface("body") = {1, 2};
