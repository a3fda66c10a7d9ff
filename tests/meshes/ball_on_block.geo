// A full ball (R = 0.5, centre (0, 0, 0.5)) resting at its pole on a block [-1,1]^2 x [-0.5,0]
// (tests/body_friction.rs): two volumes meshed independently (no shared node), finer (h / 2)
// within 0.3 of the pole. Groups: ball, block (volumes), ball_surf (the whole sphere),
// block_top, block_bottom.
SetFactory("OpenCASCADE");
If (!Exists(h))
  h = 0.1;
EndIf
Sphere(1) = {0, 0, 0.5, 0.5};
Box(2) = {-1, -1, -0.5, 2, 2, 0.5};
Physical Volume("ball") = {1};
Physical Volume("block") = {2};
Physical Surface("ball_surf") = {1};
top() = Surface In BoundingBox{-1.1, -1.1, -0.01, 1.1, 1.1, 0.01};
bottom() = Surface In BoundingBox{-1.1, -1.1, -0.51, 1.1, 1.1, -0.49};
Physical Surface("block_top") = {top()};
Physical Surface("block_bottom") = {bottom()};
Field[1] = Ball;
Field[1].Radius = 0.3;
Field[1].Thickness = 0.3;
Field[1].VIn = h / 2;
Field[1].VOut = 2 * h;
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
