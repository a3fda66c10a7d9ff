// indent2d_sym: the block [-1,1] x [0,1] of cases/blocks/indent2d.geo with a mesh that is
// exactly mirror-symmetric about x = 0 (tests/contact_blocks.rs demands a symmetric solution).
// Two transfinite halves whose corner lists are mirror images of each other, so the grid
// (i, j) of the left half is the mirror of the right half's, diagonals included.
// Graded towards the top centre (0, 1), where the rigid circle indents the block.
// Groups: "bottom" (y = 0), "top" (y = 1, contact), "left", "right", "body".
// gmsh -2 indent2d_sym.geo -format msh41 -o indent2d_sym.msh
If (!Exists(nx)) nx = 41; EndIf   // nodes per half along x
If (!Exists(ny)) ny = 25; EndIf   // nodes along y
If (!Exists(gx)) gx = 1.08; EndIf // growth factor away from x = 0
If (!Exists(gy)) gy = 1.12; EndIf // growth factor away from y = 1
Point(1) = {0, 0, 0};
Point(2) = {1, 0, 0};
Point(3) = {1, 1, 0};
Point(4) = {0, 1, 0};
Point(5) = {-1, 0, 0};
Point(6) = {-1, 1, 0};
// right half: lines oriented away from x = 0 and away from y = 1
Line(1) = {1, 2};  // bottom right
Line(2) = {3, 2};  // right side, from the top down
Line(3) = {4, 3};  // top right
Line(4) = {4, 1};  // centre line, from the top down
// left half: the mirror images
Line(5) = {1, 5};  // bottom left
Line(6) = {6, 5};  // left side, from the top down
Line(7) = {4, 6};  // top left
Transfinite Curve{1, 3, 5, 7} = nx Using Progression gx;
Transfinite Curve{2, 4, 6} = ny Using Progression gy;
Curve Loop(1) = {1, -2, -3, 4};
Plane Surface(1) = {1};
Curve Loop(2) = {-4, 7, 6, -5};
Plane Surface(2) = {2};
Transfinite Surface{1} = {1, 2, 3, 4};
Transfinite Surface{2} = {1, 5, 6, 4};
Physical Curve("bottom") = {1, 5};
Physical Curve("right") = {2};
Physical Curve("top") = {3, 7};
Physical Curve("left") = {6};
Physical Surface("body") = {1, 2};
