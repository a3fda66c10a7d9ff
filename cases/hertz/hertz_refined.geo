// Unit disk for the 2D Hertz case, refined under the contact zone (for convergence studies).
// Same geometry, arcs and physical groups as hertz.geo (see there); differences:
//
// Parameters (gmsh -setnumber NAME VALUE):
//   L  level, default 3: the load arc has 2*2^L and each free side arc 5*2^L segments,
//      exactly as in hertz.geo.
//   R  extra refinement of the contact arc, default 2: the contact arc (bottom quarter) has
//      4*2^(L+R) segments (two 45° arcs of 2*2^(L+R)), i.e. the contact spacing of plain level
//      L+R: hc = (pi/2) / (4*2^(L+R)) = 0.3927 / 2^(L+R). With R = 0 the boundary is the one of
//      hertz.geo. Boundary total: 12*2^L + 4*2^(L+R) segments.
//   Z  radius of the zone around the bottom point (0,-1) meshed uniformly with size hc,
//      default 0.3 (the Hertz half width is b = 0.094).
//   G  growth rate of the element size away from the zone, the contact arc and the
//      boundary, default 0.3 (as hertz.geo).
//   H  maximal element size, default 0.22 (as hertz.geo).
//
// Size field = min of
//   hb + G * (1 - |x|)                     (the grading of hertz.geo, hb = 2pi/(16*2^L))
//   hc + G * dist(x, contact arc)           (grades away from the fine contact arc)
//   hc + G * max(0, |x - (0,-1)| - Z)       (uniform zone under the contact)
// and clipped to H.  The zone dominates the cost: about 0.16 / hc^2 points (Z = 0.3).
//
// Points (R = 2, Z = 0.3): L0..L7 = 126, 279, 720, 2067, 6309, 21086, 75120, 280556.
// Measured p_max (frictionless solver, Hertz 0.103483): L4 0.103766, L5 0.103725,
// L6 0.103720; the plain family stalls near 0.1053 (L6, L7). A smaller zone costs accuracy:
// L6 with Z = 0.15 (26421 points) 0.103852, Z = 0.1 (16954 points) 0.103952.
//
// gmsh -2 hertz_refined.geo -setnumber L 3 -format msh41 -bin -o meshes/hertz_refined_L3.msh
// (use scripts/mesh hertz 3 --refined)
If (!Exists(L)) L = 3; EndIf
If (!Exists(R)) R = 2; EndIf
If (!Exists(Z)) Z = 0.3; EndIf
If (!Exists(G)) G = 0.3; EndIf
If (!Exists(H)) H = 0.22; EndIf

n = 2^L;
nc = 2^(L + R);
hb = 2 * Pi / (16 * n);
hc = 2 * Pi / (16 * nc);

Point(1) = {0, 0, 0, hb};                                     // centre
Point(2) = {0, -1, 0, hc};                                    // 3pi/2, bottom point
Point(3) = {Cos(7*Pi/4), Sin(7*Pi/4), 0, hc};                 // contact end (right)
Point(4) = {Cos(3*Pi/8), Sin(3*Pi/8), 0, hb};                 // load end (right)
Point(5) = {Cos(5*Pi/8), Sin(5*Pi/8), 0, hb};                 // load end (left)
Point(6) = {Cos(5*Pi/4), Sin(5*Pi/4), 0, hc};                 // contact end (left)

Circle(1) = {2, 1, 3};   // contact, 270° .. 315°
Circle(2) = {3, 1, 4};   // free, 315° .. 427.5°
Circle(3) = {4, 1, 5};   // load, 67.5° .. 112.5°
Circle(4) = {5, 1, 6};   // free, 112.5° .. 225°
Circle(5) = {6, 1, 2};   // contact, 225° .. 270°

Transfinite Curve{1, 5} = 2 * nc + 1;
Transfinite Curve{3} = 2 * n + 1;
Transfinite Curve{2, 4} = 5 * n + 1;

Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Point{1} In Surface{1};

// Field 2: distance to the contact arc, sampled at its 4*2^(L+R)+2 segment ends.
Field[1] = MathEval;
Field[1].F = Sprintf("%.17g + %.17g * (1 - Sqrt(x*x + y*y))", hb, G);
Field[2] = Distance;
Field[2].CurvesList = {1, 5};
Field[2].NumPointsPerCurve = 2 * nc + 1;
Field[3] = MathEval;
Field[3].F = Sprintf("%.17g + %.17g * F2", hc, G);
Field[4] = Distance;
Field[4].PointsList = {2};
Field[5] = Threshold;
Field[5].InField = 4;
Field[5].SizeMin = hc;
Field[5].SizeMax = H;
Field[5].DistMin = Z;
Field[5].DistMax = Z + (H - hc) / G;
Field[6] = Min;
Field[6].FieldsList = {1, 3, 5};
Background Field = 6;
Mesh.MeshSizeMax = H;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;

Physical Curve("contact") = {5, 1};
Physical Curve("load") = {3};
Physical Curve("free") = {2, 4};
Physical Surface("body") = {1};
