// Mindlin between two elastic bodies (3D), half-symmetric (y >= 0), meshed independently
// (OpenCASCADE): a lens — the half cylinder of radius W = 1.5 (axis z, 0 <= z <= T = 1) whose
// bottom is a cap of the sphere of radius R = 10 centred at (0, 0, R), touching z = 0 at the
// origin — on the half block [-1.5, 1.5] x [0, 1.5] x [-1.5, 0]. The large R keeps the contact
// narrow against the radius (a/R about 0.016 at the case's approach): Mindlin's half-space
// theory, and the slave and master normals within 1° of each other across the zone.
//
// Parameters (gmsh -setnumber NAME VALUE):
//   L  level, default 1: size hc = h0 / sqrt(2)^L within Z of the origin (both bodies)
//   h0 size of level 0, default 0.02;  Z  radius of the uniform zone, default 0.22
//   G  growth of the size beyond, default 0.35;  H  maximal size, default 0.3
//
// Groups: volumes "lens", "block"; surfaces "lens_top" (z = T), "sym_y" (y = 0, both bodies),
// "lens_contact" (the spherical cap), "block_contact" (z = 0), "block_bottom" (z = -1.5).
// gmsh -3 mindlin_bodies3d.geo -setnumber L 1 -format msh41 -bin -o mindlin_bodies3d_L1.msh
SetFactory("OpenCASCADE");
If (!Exists(L)) L = 1; EndIf
If (!Exists(h0)) h0 = 0.02; EndIf
If (!Exists(Z)) Z = 0.22; EndIf
If (!Exists(G)) G = 0.35; EndIf
If (!Exists(H)) H = 0.3; EndIf
R = 10; W = 1.5; T = 1.0; B = 1.5; D = 1.5;
hc = h0 / Sqrt(2)^L;
Sphere(1) = {0, 0, R, R};
Cylinder(2) = {0, 0, 0, 0, 0, T, W};
BooleanIntersection(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Box(5) = {-W, 0, 0, 2*W, W, T};
BooleanIntersection(6) = { Volume{3}; Delete; }{ Volume{5}; Delete; };
Box(4) = {-B, 0, -D, 2*B, B, D};
e = 1e-6;
Field[1] = MathEval;
Field[1].F = Sprintf("%.17g + %.17g * Max(0, Sqrt(x*x+y*y+z*z) - %.17g)", hc, G, Z);
Background Field = 1;
Mesh.MeshSizeMax = H;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;
sy() = Surface In BoundingBox{-W-e, -e, -e, W+e, e, T+e};
st() = Surface In BoundingBox{-W-e, -e, T-e, W+e, W+e, T+e};
by() = Surface In BoundingBox{-B-e, -e, -D-e, B+e, e, e};
btop() = Surface In BoundingBox{-B-e, -e, -e, B+e, B+e, e};
bbot() = Surface In BoundingBox{-B-e, -e, -D-e, B+e, B+e, -D+e};
// the cap: the lens' boundary below z = 0.2 but for its mirror face
sb() = Boundary{ Volume{6}; };
sc() = {};
For i In {0:#sb()-1}
  If (sb(i) != sy(0) && sb(i) != st(0))
    bb() = BoundingBox Surface{sb(i)};
    If (bb(5) < 0.2)
      sc() += sb(i);
    EndIf
  EndIf
EndFor
Physical Volume("lens") = {6};
Physical Volume("block") = {4};
Physical Surface("lens_top") = st();
Physical Surface("sym_y") = {sy(), by()};
Physical Surface("lens_contact") = sc();
Physical Surface("block_contact") = btop();
Physical Surface("block_bottom") = bbot();
