// Two unit cubes side by side, meshed apart: their shared face has two sets of nodes unless
// `joined` is 1 (BooleanFragments makes the mesh conformal). tests/warnings.rs (unjoined_nodes).
SetFactory("OpenCASCADE");
If (!Exists(h))
  h = 0.25;
EndIf
If (!Exists(joined))
  joined = 0;
EndIf
Box(1) = {0, 0, 0, 1, 1, 1};
Box(2) = {1, 0, 0, 1, 1, 1};
If (joined)
  BooleanFragments{ Volume{1}; Delete; }{ Volume{2}; Delete; }
EndIf
Mesh.CharacteristicLengthMax = h;
eps = 1e-6;
Physical Surface("bottom") = Surface In BoundingBox{-eps, -eps, -eps, 2 + eps, 1 + eps, eps};
Physical Surface("top") = Surface In BoundingBox{-eps, -eps, 1 - eps, 2 + eps, 1 + eps, 1 + eps};
Physical Volume("body") = {1, 2};
