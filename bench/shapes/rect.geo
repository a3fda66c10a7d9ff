// The rectangle [-1,1] x [0,0.5]: its bottom the contact boundary, its top ("top") held;
// graded from h at the bottom to 3h at the top.
// Meshed by scripts/bench-shapes (h 0.008 and 0.003): gmsh -2 rect.geo -setnumber h H -format msh41 -o ../meshes/rect_hH.msh
If (!Exists(h)) h = 0.01; EndIf
Point(1) = {-1,0,0,h}; Point(2) = {1,0,0,h}; Point(3) = {1,0.5,0,3*h}; Point(4) = {-1,0.5,0,3*h};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};
Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};
Physical Curve("contact") = {1}; Physical Curve("top") = {3}; Physical Curve("sides") = {2,4};
Physical Surface("body") = {1};
