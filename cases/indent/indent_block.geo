// indent_block: the body of the indentation checks (scripts/bench-indent, tests/indentation.rs).
// A block under the plane z = 0 (its top, the contact boundary), indented at the origin along
// -z. quarter (half = 0): [0,L] x [0,L] x [-L,0] with the mirror planes x = 0 and y = 0;
// half (half = 1): [-L,L] x [0,L] x [-L,0] with the mirror plane y = 0 (for a Berkovich pyramid
// with a face towards +x). Lengths in units of the contact radius a ~ 1.
// The circle r = ring (default 1: the radius of the flat punch; 0: none) on the top face is
// meshed as a line of nodes, of size hr (default hc; the punch's singular edge wants it finer). Size field: hc within the distance r0 of the origin, growing by k per unit distance beyond,
// at most L/4. Groups: "top" (z = 0), "bottom" (z = -L), "symx" (x = 0, quarter only),
// "symy" (y = 0), "body"; the far sides x = +-L, y = L are free and unnamed.
// gmsh -3 indent_block.geo -setnumber L 50 -setnumber hc 0.1 -format msh41 -bin -o X.msh
//   (or scripts/mesh indent ...)
SetFactory("OpenCASCADE");
If (!Exists(L)) L = 50; EndIf
If (!Exists(hc)) hc = 0.1; EndIf
If (!Exists(k)) k = 0.3; EndIf
If (!Exists(r0)) r0 = 1.3; EndIf
If (!Exists(half)) half = 0; EndIf
If (!Exists(ring)) ring = 1; EndIf
If (!Exists(hr)) hr = hc; EndIf
hmax = L / 4;
x0 = -L * half;
Box(1) = {x0, 0, -L, L - x0, L, L};
If (ring > 0)
  // the circle r = ring on the top face is a line of nodes (the edge of a flat punch)
  Circle(100) = {0, 0, 0, ring, 0, Pi * (1 + half) / 2};
  BooleanFragments{ Volume{1}; Delete; }{ Curve{100}; Delete; }
EndIf
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, %g + %g * Max(0, Sqrt(x*x + y*y + z*z) - %g))", hmax, hc, k, r0);
Background Field = 1;
If (ring > 0 && hr < hc)
  // finer towards the ring: hr on it, growing by 0.3 per unit distance from it
  Field[2] = MathEval;
  Field[2].F = Sprintf("%g + 0.3 * Sqrt((Sqrt(x*x + y*y) - %g)^2 + z*z)", hr, ring);
  Field[3] = Min;
  Field[3].FieldsList = {1, 2};
  Background Field = 3;
EndIf
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
eps = 1e-6 * L;
top() = Surface In BoundingBox{x0 - eps, -eps, -eps, L + eps, L + eps, eps};
bottom() = Surface In BoundingBox{x0 - eps, -eps, -L - eps, L + eps, L + eps, -L + eps};
symy() = Surface In BoundingBox{x0 - eps, -eps, -L - eps, L + eps, eps, eps};
Physical Surface("top") = {top()};
Physical Surface("bottom") = {bottom()};
Physical Surface("symy") = {symy()};
If (!half)
  symx() = Surface In BoundingBox{-eps, -eps, -L - eps, eps, L + eps, eps};
  Physical Surface("symx") = {symx()};
EndIf
Physical Volume("body") = {1};
