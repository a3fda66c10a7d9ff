// A full ball of radius 1 (centre at the origin), floating: no Dirichlet data, no symmetry
// plane. A downward pressure on its top cap (z >= 0.8) presses it onto the rigid plane z = -1;
// the lower hemisphere is the contact candidate boundary (ball3d.toml).
// Mesh size h near the south pole (0, 0, -1) up to the distance 2*r, growing linearly to hmax
// at the distance dmax:  gmsh -3 ball3d.geo -setnumber h 0.01 -format msh41 -bin -o ball3d.msh
// With -setnumber zone H (> 0) the cap z <= -1 + H is also the group "zone" (a part of
// "contact"): a linear solve can clamp the contact zone alone (scripts/bench-contact).
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.02, r = 0.1, hmax = 0.12, dmax = 0.8, zone = 0 ];
Sphere(1) = {0, 0, 0, 1};
Rectangle(10) = {-2, -2, 0, 4, 4};
Rectangle(11) = {-2, -2, 0.8, 4, 4};
zs() = {0, 0.8};
If (zone > 0)
  Rectangle(12) = {-2, -2, -1 + zone, 4, 4};
  BooleanFragments{ Volume{1}; Delete; }{ Surface{10, 11, 12}; Delete; }
  zs() += {-1 + zone};
Else
  BooleanFragments{ Volume{1}; Delete; }{ Surface{10, 11}; Delete; }
EndIf
eps = 1e-6;
// the parts of the cutting planes outside the ball
For j In {0 : #zs() - 1}
  zc = zs(j);
  pcs() = Surface In BoundingBox{-2.1, -2.1, zc - eps, 2.1, 2.1, zc + eps};
  For i In {0 : #pcs() - 1}
    bb() = BoundingBox Surface{pcs(i)};
    If (bb(3) - bb(0) > 2.5)
      Recursive Delete { Surface{pcs(i)}; }
    EndIf
  EndFor
EndFor
lower() = Surface In BoundingBox{-1 - eps, -1 - eps, -1 - eps, 1 + eps, 1 + eps, eps};
lower() -= Surface In BoundingBox{-1 - eps, -1 - eps, -eps, 1 + eps, 1 + eps, eps};
top() = Surface In BoundingBox{-1 - eps, -1 - eps, 0.8 - eps, 1 + eps, 1 + eps, 1 + eps};
top() -= Surface In BoundingBox{-1 - eps, -1 - eps, 0.8 - eps, 1 + eps, 1 + eps, 0.8 + eps};
Physical Volume("body") = {Volume{:}};
Physical Surface("load") = {top()};
If (zone > 0)
  lower() -= Surface In BoundingBox{-1 - eps, -1 - eps, -1 + zone - eps, 1 + eps, 1 + eps, -1 + zone + eps};
EndIf
Physical Surface("contact") = {lower()};
If (zone > 0)
  cap() = Surface In BoundingBox{-1 - eps, -1 - eps, -1 - eps, 1 + eps, 1 + eps, -1 + zone + eps};
  cap() -= Surface In BoundingBox{-1 - eps, -1 - eps, -1 + zone - eps, 1 + eps, 1 + eps, -1 + zone + eps};
  Physical Surface("zone") = {cap()};
EndIf
Field[1] = MathEval;
Field[1].F = Sprintf("%g + (%g - %g) * Max(0, Min(1, (Sqrt(x*x + y*y + (z+1)*(z+1)) - 2*%g) / (%g - 2*%g)))", h, hmax, h, r, dmax, r);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm3D = 10;
