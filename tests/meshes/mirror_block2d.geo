// The right half [0, 2] x [0, 1] of a block, graded towards the middle of its top (0, 1):
// mirror line x = 0 ("sym"), "bottom" (y = 0), "top" (y = 1), surface "body". h: size far
// from (0, 1) (the size there h / 6). tests/symmetry.rs mirrors it into the whole block.
If (!Exists(h)) h = 0.12; EndIf
Point(1) = {0, 0, 0}; Point(2) = {2, 0, 0}; Point(3) = {2, 1, 0}; Point(4) = {0, 1, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Field[1] = MathEval;
Field[1].F = Sprintf("Min(%g, %g + 0.3 * Max(0, Sqrt(x^2 + (y-1)^2) - 0.2))", h, h / 6);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeFromCurvature = 0;
Physical Curve("bottom") = {1}; Physical Curve("top") = {3}; Physical Curve("sym") = {4};
Physical Surface("body") = {1};
