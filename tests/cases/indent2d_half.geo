// indent2d_half: the right half (x >= 0) of indent2d_sym.geo, meshed exactly as that mesh's
// right half (the same transfinite surface), for the symmetry-row test in
// tests/contact_blocks.rs: u_x = 0 on x = 0 ("sym"), where the contact node (0, 1) keeps its
// contact row (its normal is orthogonal to the prescribed component).
// Groups: "bottom" (y = 0), "top" (y = 1, contact), "right", "sym" (x = 0), "body".
// gmsh -2 indent2d_half.geo -format msh41 -o indent2d_half.msh
If (!Exists(nx)) nx = 41; EndIf   // nodes per half along x
If (!Exists(ny)) ny = 25; EndIf   // nodes along y
If (!Exists(gx)) gx = 1.08; EndIf // growth factor away from x = 0
If (!Exists(gy)) gy = 1.12; EndIf // growth factor away from y = 1
Point(1) = {0, 0, 0};
Point(2) = {1, 0, 0};
Point(3) = {1, 1, 0};
Point(4) = {0, 1, 0};
// right half: lines oriented away from x = 0 and away from y = 1
Line(1) = {1, 2};  // bottom right
Line(2) = {3, 2};  // right side, from the top down
Line(3) = {4, 3};  // top right
Line(4) = {4, 1};  // centre line, from the top down
Transfinite Curve{1, 3} = nx Using Progression gx;
Transfinite Curve{2, 4} = ny Using Progression gy;
Curve Loop(1) = {1, -2, -3, 4};
Plane Surface(1) = {1};
Transfinite Surface{1} = {1, 2, 3, 4};
Physical Curve("bottom") = {1};
Physical Curve("right") = {2};
Physical Curve("top") = {3};
Physical Curve("sym") = {4};
Physical Surface("body") = {1};
