// Two elastic bodies in Hertz line contact, half-symmetric (x >= 0), meshed independently:
// a quarter disk of radius R (centre (0, R), its lowest point at the origin; the quarter of
// the half disk whose flat top y = R is pushed down) and a half block [0, W] x [-D, 0] under
// it. They touch at the origin only (two distinct nodes there, one per body).
//
// Parameters (gmsh -setnumber NAME VALUE):
//   L  level, default 2: contact size hc = h0 / 2^L on the disk, K * hc on the block
//   h0 contact size of level 0, default 0.04
//   K  block / disk size ratio at the contact, default 1.5 (non-matching interface meshes)
//   Z  radius of the zone around the origin meshed uniformly, default 0.2 (a ~ 0.1)
//   G  growth rate of the element size away from the zone, default 0.3
//   H  maximal element size, default 0.25
//   R, W, D  disk radius 1, block half width 2, block depth 2
//   F  1: the full model instead (the half disk on the block [-W, W] x [-D, 0], no mirror
//      plane; the block's top has a node at the origin), default 0
//
// Groups: surfaces "disk", "block"; curves "disk_top" (y = R), "sym" (x = 0, both bodies),
// "disk_contact" (the arc from the lowest point to 30°), "disk_free" (the rest of the arc),
// "block_contact" (y = 0, 0 <= x <= 0.45), "block_top" (the rest of y = 0), "block_right",
// "block_bottom" (y = -D); the full model has no "sym", its contact groups are symmetric
// ("disk_contact" from -30° to 30°, "block_contact" -0.45 <= x <= 0.45), "disk_free" and
// "block_right" both sides.
//
// gmsh -2 hertz_bodies.geo -setnumber L 2 [-setnumber F 1] -format msh41 -bin -o hertz_bodies_L2.msh
// (scripts/bench-bodies makes its meshes so, in bench/meshes/)
If (!Exists(L)) L = 2; EndIf
If (!Exists(h0)) h0 = 0.04; EndIf
If (!Exists(K)) K = 1.5; EndIf
If (!Exists(Z)) Z = 0.2; EndIf
If (!Exists(G)) G = 0.3; EndIf
If (!Exists(H)) H = 0.25; EndIf
If (!Exists(R)) R = 1; EndIf
If (!Exists(W)) W = 2; EndIf
If (!Exists(D)) D = 2; EndIf
If (!Exists(F)) F = 0; EndIf

hc = h0 / 2^L;
hb = K * hc;
tc = Pi / 6;      // the disk's contact arc: 0 .. 30°
xc = 0.45;        // the block's contact segment: 0 .. xc

If (F == 0)
// disk
Point(1) = {0, R, 0, H};                                 // centre
Point(2) = {0, 0, 0, hc};                                // lowest point
Point(3) = {R * Sin(tc), R - R * Cos(tc), 0, hc};        // end of the contact arc
Point(4) = {R, R, 0, H};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Line(3) = {4, 1};
Line(4) = {1, 2};
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

// block
Point(11) = {0, 0, 0, hb};
Point(12) = {xc, 0, 0, hb};
Point(13) = {W, 0, 0, H};
Point(14) = {W, -D, 0, H};
Point(15) = {0, -D, 0, H};
Line(11) = {11, 12};
Line(12) = {12, 13};
Line(13) = {13, 14};
Line(14) = {14, 15};
Line(15) = {15, 11};
Curve Loop(11) = {11, 12, 13, 14, 15};
Plane Surface(11) = {11};

Else
// disk: the lower half, its top through the centre
Point(1) = {0, R, 0, H};
Point(2) = {0, 0, 0, hc};
Point(3) = {R * Sin(tc), R - R * Cos(tc), 0, hc};
Point(4) = {R, R, 0, H};
Point(5) = {-R, R, 0, H};
Point(6) = {-R * Sin(tc), R - R * Cos(tc), 0, hc};
Circle(1) = {2, 1, 3};
Circle(2) = {3, 1, 4};
Line(3) = {4, 1};
Line(4) = {1, 5};
Circle(5) = {5, 1, 6};
Circle(6) = {6, 1, 2};
Curve Loop(1) = {1, 2, 3, 4, 5, 6};
Plane Surface(1) = {1};

// block
Point(11) = {0, 0, 0, hb};
Point(12) = {xc, 0, 0, hb};
Point(13) = {W, 0, 0, H};
Point(14) = {W, -D, 0, H};
Point(15) = {-W, -D, 0, H};
Point(16) = {-W, 0, 0, H};
Point(17) = {-xc, 0, 0, hb};
Line(11) = {11, 12};
Line(12) = {12, 13};
Line(13) = {13, 14};
Line(14) = {14, 15};
Line(15) = {15, 16};
Line(16) = {16, 17};
Line(17) = {17, 11};
Curve Loop(11) = {11, 12, 13, 14, 15, 16, 17};
Plane Surface(11) = {11};
EndIf

// sizes: uniform within Z of the origin (hc in the disk, hb in the block), growing by G beyond
Field[1] = Distance;
Field[1].PointsList = {2};
Field[2] = MathEval;
Field[2].F = Sprintf("%.17g + %.17g * Max(0, F1 - %.17g)", hc, G, Z);
Field[3] = Restrict;
Field[3].InField = 2;
Field[3].SurfacesList = {1};
Field[3].CurvesList = {1, 2, 3, 4, 5, 6};
Field[4] = MathEval;
Field[4].F = Sprintf("%.17g + %.17g * Max(0, F1 - %.17g)", hb, G, Z);
Field[5] = Restrict;
Field[5].InField = 4;
Field[5].SurfacesList = {11};
Field[5].CurvesList = {11, 12, 13, 14, 15, 16, 17};
Field[6] = Min;
Field[6].FieldsList = {3, 5};
Background Field = 6;
Mesh.MeshSizeMax = H;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;

Physical Surface("disk") = {1};
Physical Surface("block") = {11};
If (F == 0)
  Physical Curve("disk_top") = {3};
  Physical Curve("sym") = {4, 15};
  Physical Curve("disk_contact") = {1};
  Physical Curve("disk_free") = {2};
  Physical Curve("block_contact") = {11};
  Physical Curve("block_top") = {12};
  Physical Curve("block_right") = {13};
  Physical Curve("block_bottom") = {14};
Else
  Physical Curve("disk_top") = {3, 4};
  Physical Curve("disk_contact") = {6, 1};
  Physical Curve("disk_free") = {2, 5};
  Physical Curve("block_contact") = {17, 11};
  Physical Curve("block_top") = {12, 16};
  Physical Curve("block_right") = {13, 15};
  Physical Curve("block_bottom") = {14};
EndIf
