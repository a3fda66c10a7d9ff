// Two elastic cylinders in line contact, meshed independently (Cattaneo–Mindlin between two
// bodies): the lower half of a disk of radius R centred at (0, R) (the upper body, its flat
// side y = R through the centre) on the upper half of a disk of radius R centred at (0, -R)
// (the lower body, its flat side y = -R). They touch at the origin only (two distinct nodes
// there, one per body); 1/R* = 1/R + 1/R = 2/R.
//
// Parameters (gmsh -setnumber NAME VALUE):
//   L  level, default 2: contact size hc = h0 / 2^L on the upper body, K * hc on the lower
//   h0 contact size of level 0, default 0.0016
//   K  lower / upper size ratio at the contact, default 1.5 (non-matching interface meshes)
//   Z  radius of the zone around the origin meshed uniformly, default 0.008 (the case's
//      a = 0.005)
//   G  growth rate of the element size away from the zone, default 0.3
//   H  maximal element size, default 0.25
//   R  radius of both cylinders, default 1
//
// Groups: surfaces "upper", "lower"; curves "upper_top" (y = R), "upper_contact" (the arc
// from -30° to 30° around the lowest point), "upper_free" (the rest of its arc), "lower_bottom"
// (y = -R), "lower_contact" (-30° to 30° around the highest point), "lower_free".
//
// gmsh -2 cattaneo_bodies.geo -setnumber L 2 -format msh41 -bin -o cattaneo_bodies_L2.msh
// (scripts/mesh bodies 2 --cattaneo; scripts/bench-bodies --cattaneo makes its own)
If (!Exists(L)) L = 2; EndIf
If (!Exists(h0)) h0 = 0.0016; EndIf
If (!Exists(K)) K = 1.5; EndIf
If (!Exists(Z)) Z = 0.008; EndIf
If (!Exists(G)) G = 0.3; EndIf
If (!Exists(H)) H = 0.25; EndIf
If (!Exists(R)) R = 1; EndIf

hc = h0 / 2^L;
hl = K * hc;
tc = Pi / 6;      // half the opening of each contact arc: 30°
sc = R * Sin(tc);
yc = R - R * Cos(tc);

// upper body: the lower half disk
Point(1) = {0, R, 0, H};          // centre
Point(2) = {0, 0, 0, hc};         // lowest point
Point(3) = {sc, yc, 0, hc};
Point(4) = {R, R, 0, H};
Point(5) = {-R, R, 0, H};
Point(6) = {-sc, yc, 0, hc};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Line(3) = {4, 5};
Circle(4) = {5, 1, 6};
Circle(5) = {6, 1, 2};
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

// lower body: the upper half disk
Point(11) = {0, -R, 0, H};        // centre
Point(12) = {0, 0, 0, hl};        // highest point
Point(13) = {-sc, -yc, 0, hl};
Point(14) = {-R, -R, 0, H};
Point(15) = {R, -R, 0, H};
Point(16) = {sc, -yc, 0, hl};
Circle(11) = {12, 11, 13};
Circle(12) = {13, 11, 14};
Line(13) = {14, 15};
Circle(14) = {15, 11, 16};
Circle(15) = {16, 11, 12};
Curve Loop(11) = {11, 12, 13, 14, 15};
Plane Surface(11) = {11};

// sizes: uniform within Z of the origin (hc in the upper body, hl in the lower), growing by G
Field[1] = Distance;
Field[1].PointsList = {2};
Field[2] = MathEval;
Field[2].F = Sprintf("%.17g + %.17g * Max(0, F1 - %.17g)", hc, G, Z);
Field[3] = Restrict;
Field[3].InField = 2;
Field[3].SurfacesList = {1};
Field[3].CurvesList = {1, 2, 3, 4, 5};
Field[4] = MathEval;
Field[4].F = Sprintf("%.17g + %.17g * Max(0, F1 - %.17g)", hl, G, Z);
Field[5] = Restrict;
Field[5].InField = 4;
Field[5].SurfacesList = {11};
Field[5].CurvesList = {11, 12, 13, 14, 15};
Field[6] = Min;
Field[6].FieldsList = {3, 5};
Background Field = 6;
Mesh.MeshSizeMax = H;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;

Physical Surface("upper") = {1};
Physical Surface("lower") = {11};
Physical Curve("upper_top") = {3};
Physical Curve("upper_contact") = {5, 1};
Physical Curve("upper_free") = {2, 4};
Physical Curve("lower_bottom") = {13};
Physical Curve("lower_contact") = {11, 15};
Physical Curve("lower_free") = {12, 14};
