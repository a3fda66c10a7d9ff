// An ellipse, half axes 1 and 0.6, touching the plane y = 0 at the origin; its lower half the
// contact boundary, its upper half loaded; elements graded from 0.003 at the touching point
// (within 0.03) to 0.03 (from 0.5 away). tests/coulomb_passes.rs.
SetFactory("Built-in");
c = newp; Point(c) = {0, 0.6, 0};
pl = newp; Point(pl) = {-1, 0.6, 0};
pr = newp; Point(pr) = {1, 0.6, 0};
pb = newp; Point(pb) = {0, 0, 0};
pt = newp; Point(pt) = {0, 1.2, 0};
e1 = newl; Ellipse(e1) = {pl, c, pr, pb};
e2 = newl; Ellipse(e2) = {pb, c, pr, pr};
e3 = newl; Ellipse(e3) = {pr, c, pr, pt};
e4 = newl; Ellipse(e4) = {pt, c, pr, pl};
Curve Loop(1) = {e1, e2, e3, e4};
Plane Surface(1) = {1};
Physical Curve("contact") = {e1, e2};
Physical Curve("load") = {e3, e4};
Physical Surface("body") = {1};
Field[1] = Distance;
Field[1].PointsList = {pb};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = 0.003;
Field[2].SizeMax = 0.03;
Field[2].DistMin = 0.03;
Field[2].DistMax = 0.5;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
