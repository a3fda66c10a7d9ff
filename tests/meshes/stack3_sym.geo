// A half model (mirror line x = 0) of three bodies stacked on a rigid plane y = 0
// (tests/load_steps.rs): block [0,1]x[0,0.5], plate [0,0.6]x[0.5,0.5+t] on it, quarter disk R = 0.5
// centre (0,1+t) on the plate; meshed apart, graded towards the axis (sizes hf to hc).
If (!Exists(t)) t = 0.1; EndIf
If (!Exists(hf)) hf = 0.005; EndIf
If (!Exists(hc)) hc = 0.1; EndIf
Point(1) = {0,0,0,hc}; Point(2) = {1,0,0,hc}; Point(3) = {1,0.5,0,hc}; Point(4) = {0,0.5,0,hf*2};
Line(1) = {1,2}; Line(2) = {2,3}; Line(3) = {3,4}; Line(4) = {4,1};
Curve Loop(1) = {1,2,3,4}; Plane Surface(1) = {1};
Point(11) = {0,0.5,0,hf*2}; Point(12) = {0.6,0.5,0,hc/2}; Point(13) = {0.6,0.5+t,0,hc/2}; Point(14) = {0,0.5+t,0,hf};
Line(11) = {11,12}; Line(12) = {12,13}; Line(13) = {13,14}; Line(14) = {14,11};
Curve Loop(11) = {11,12,13,14}; Plane Surface(11) = {11};
cy = 1.0 + t;
Point(20) = {0,cy,0,hc}; Point(21) = {0,cy-0.5,0,hf*1.5}; Point(22) = {0.5,cy,0,hc};
Circle(21) = {21,20,22}; Line(22) = {22,20}; Line(23) = {20,21};
Curve Loop(21) = {21,22,23}; Plane Surface(21) = {21};
Physical Surface("block") = {1}; Physical Surface("plate") = {11}; Physical Surface("disk") = {21};
Physical Curve("block_bottom") = {1}; Physical Curve("block_top") = {3};
Physical Curve("plate_bottom") = {11}; Physical Curve("plate_top") = {13};
Physical Curve("disk_arc") = {21}; Physical Curve("disk_top") = {22};
Physical Curve("sym") = {4,14,23};
Field[1] = Distance; Field[1].PointsList = {4,14,21}; Field[1].NumPointsPerCurve = 100;
Field[2] = Threshold; Field[2].InField = 1; Field[2].SizeMin = hf; Field[2].SizeMax = hc;
Field[2].DistMin = 0.05; Field[2].DistMax = 0.5;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0; Mesh.MeshSizeFromPoints = 0; Mesh.MeshSizeFromCurvature = 0;
