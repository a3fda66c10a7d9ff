// Hertz point contact between two elastic bodies, quarter-symmetric (x >= 0, y >= 0), meshed
// independently (OpenCASCADE): the quarter of the lower half ball of radius R = 1 (centre
// (0, 0, R), its lowest point at the origin, its flat top z = R pushed down) and the quarter
// block [0, 1.5]² x [-1.5, 0] under it; they touch at the origin only.
//
// Parameters (gmsh -setnumber NAME VALUE):
//   L  level, default 1: size hc = h0 / 2^L within Z of the origin (both bodies)
//   h0 size of level 0, default 0.04;  Z  radius of the uniform zone, default 0.15
//   G  growth of the size beyond, default 0.3;  H  maximal size, default 0.3
// (K is unused here: both bodies have the same size field.)
//
// Groups: volumes "ball", "block"; surfaces "ball_top" (z = R), "sym_x" (x = 0, both bodies),
// "sym_y" (y = 0, both), "ball_contact" (the curved surface), "block_contact" (z = 0),
// "block_bottom" (z = -1.5).
// gmsh -3 hertz_bodies3d.geo -setnumber L 2 -format msh41 -bin -o hertz_bodies3d_L2.msh
SetFactory("OpenCASCADE");
If (!Exists(L)) L = 1; EndIf
If (!Exists(h0)) h0 = 0.04; EndIf
If (!Exists(Z)) Z = 0.15; EndIf
If (!Exists(G)) G = 0.3; EndIf
If (!Exists(H)) H = 0.3; EndIf
R = 1; W = 1.5; D = 1.5;
hc = h0 / 2^L;
Sphere(1) = {0, 0, R, R};
Box(2) = {0, 0, 0, R, R, R};
BooleanIntersection(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(4) = {0, 0, -D, W, W, D};
e = 1e-6;
Field[1] = MathEval;
Field[1].F = Sprintf("%.17g + %.17g * Max(0, Sqrt(x*x+y*y+z*z) - %.17g)", hc, G, Z);
Background Field = 1;
Mesh.MeshSizeMax = H;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
sx() = Surface In BoundingBox{-e, -e, -e, e, R+e, R+e};
sy() = Surface In BoundingBox{-e, -e, -e, R+e, e, R+e};
st() = Surface In BoundingBox{-e, -e, R-e, R+e, R+e, R+e};
sall() = Boundary{ Volume{3}; };
bx() = Surface In BoundingBox{-e, -e, -D-e, e, W+e, e};
by() = Surface In BoundingBox{-e, -e, -D-e, W+e, e, e};
btop() = Surface In BoundingBox{-e, -e, -e, W+e, W+e, e};
bbot() = Surface In BoundingBox{-e, -e, -D-e, W+e, W+e, -D+e};
Physical Volume("ball") = {3};
Physical Volume("block") = {4};
Physical Surface("ball_top") = st();
Physical Surface("sym_x") = {sx(), bx()};
Physical Surface("sym_y") = {sy(), by()};
Physical Surface("block_contact") = btop();
Physical Surface("block_bottom") = bbot();
curved() = sall();
curved() -= sx(); curved() -= sy(); curved() -= st();
Physical Surface("ball_contact") = curved();
