// A thin plate 1 x 1 x 0.01 centred on the z axis, its bottom face z = 0 ("bottom"), its top
// face ("top"), mesh size h (tests/preset_fallback.rs: one layer of cells through its
// thickness, a body that the iterative preset's multigrid preconditions poorly).
SetFactory("OpenCASCADE");
If (!Exists(h))
  h = 0.02;
EndIf
Box(1) = {-0.5, -0.5, 0, 1, 1, 0.01};
Mesh.CharacteristicLengthMax = h;
eps = 1e-6;
Physical Surface("bottom") = Surface In BoundingBox{-0.5 - eps, -0.5 - eps, -eps, 0.5 + eps, 0.5 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-0.5 - eps, -0.5 - eps, 0.01 - eps, 0.5 + eps, 0.5 + eps, 0.01 + eps};
Physical Volume("plate") = {1};
