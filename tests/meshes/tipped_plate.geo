// A plate 3 x 0.5 x 0.2 on the plane z = 0, its mesh graded towards x = 1.2 (size h there,
// 4 h away from it); "bottom" its face z = 0, "end" its face x = 3 (tests/ties.rs).
SetFactory("OpenCASCADE");
If (!Exists(h))
  h = 0.02;
EndIf
Box(1) = {0, 0, 0, 3, 0.5, 0.2};
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, %g + 5 * %g * Abs(x - 1.2))", 4 * h, h, h);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
eps = 1e-6;
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 3 + eps, 0.5 + eps, eps};
Physical Surface("end") = Surface In BoundingBox{3 - eps, -eps, -eps, 3 + eps, 0.5 + eps, 0.2 + eps};
Physical Volume("body") = {1};
