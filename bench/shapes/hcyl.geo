// A half cylinder (radius 0.5, length 1, axis along x), its flat face z = 0 ("top") held and
// its curved face ("contact") on a rigid plane: line contact in 3D.
// Meshed by scripts/bench-shapes (h 0.04 and 0.025): gmsh -3 hcyl.geo -setnumber h H -format msh41 -o ../meshes/hcyl_hH.msh
SetFactory("OpenCASCADE");
If (!Exists(h)) h = 0.05; EndIf
Cylinder(1) = {-0.5,0,0, 1,0,0, 0.5};
Box(2) = {-1,-1,0, 2,2,1};
BooleanDifference(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
Mesh.CharacteristicLengthMax = h;
Physical Volume("body") = {3};
Physical Surface("top") = {3};
Physical Surface("contact") = {1};
Physical Surface("ends") = {2,4};
