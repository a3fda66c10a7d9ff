// The quarter x, y >= 0 of the block [-1.5, 1.5]² x [-1, 0], graded towards the middle of its
// top: mirror planes x = 0 ("symx") and y = 0 ("symy"), "bottom" (z = -1), "top" (z = 0),
// volume "body". h: size far from the origin (there h / 4). tests/symmetry.rs mirrors it into
// the whole block.
SetFactory("OpenCASCADE");
If (!Exists(h)) h = 0.25; EndIf
Box(1) = {0, 0, -1, 1.5, 1.5, 1};
e = 1e-6;
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, %g + 0.4 * Max(0, Sqrt(x^2 + y^2 + z^2) - 0.25))", h, h / 4);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeFromCurvature = 0;
Physical Surface("top") = Surface In BoundingBox{-e, -e, -e, 1.5+e, 1.5+e, e};
Physical Surface("bottom") = Surface In BoundingBox{-e, -e, -1-e, 1.5+e, 1.5+e, -1+e};
Physical Surface("symx") = Surface In BoundingBox{-e, -e, -1-e, e, 1.5+e, e};
Physical Surface("symy") = Surface In BoundingBox{-e, -e, -1-e, 1.5+e, e, e};
Physical Volume("body") = {1};
