// Unit disk for the 2D Hertz case (thesis ch. 4.1; THEORY.md §6).
//
// Parameters (gmsh -setnumber NAME VALUE):
//   L  level, default 3. The boundary is split into 16*2^L equal segments:
//        contact  5pi/4 .. 7pi/4  (bottom quarter)  4*2^L segments (two 45° arcs of 2*2^L,
//                                                    so the bottom point (0,-1) is a node)
//        load     3pi/8 .. 5pi/8  (top eighth)      2*2^L segments
//        free     the two side arcs of 112.5°        5*2^L segments each
//   G  growth rate of the interior element size, default 0.3: the size field is
//        h(x) = hb + G * (1 - |x|),   hb = 2pi / (16*2^L) (the boundary segment length),
//      i.e. graded like the thesis' meshes (about 2x points per level).
//
// The centre is an embedded point: gmsh 4.8 leaves the interior of a disk whose initial
// nodes all lie on the circle unfilled at fine levels (STACK.md, "Gmsh pitfall").
//
// gmsh -2 hertz.geo -setnumber L 3 -format msh41 -bin -o meshes/hertz_L3.msh
// (use scripts/mesh hertz 3)
If (!Exists(L)) L = 3; EndIf
If (!Exists(G)) G = 0.3; EndIf
If (!Exists(H)) H = 0.22; EndIf

n = 2^L;
hb = 2 * Pi / (16 * n);

Point(1) = {0, 0, 0, hb};                                     // centre
Point(2) = {0, -1, 0, hb};                                    // 3pi/2, bottom point
Point(3) = {Cos(7*Pi/4), Sin(7*Pi/4), 0, hb};                 // contact end (right)
Point(4) = {Cos(3*Pi/8), Sin(3*Pi/8), 0, hb};                 // load end (right)
Point(5) = {Cos(5*Pi/8), Sin(5*Pi/8), 0, hb};                 // load end (left)
Point(6) = {Cos(5*Pi/4), Sin(5*Pi/4), 0, hb};                 // contact end (left)

Circle(1) = {2, 1, 3};   // contact, 270° .. 315°
Circle(2) = {3, 1, 4};   // free, 315° .. 427.5°
Circle(3) = {4, 1, 5};   // load, 67.5° .. 112.5°
Circle(4) = {5, 1, 6};   // free, 112.5° .. 225°
Circle(5) = {6, 1, 2};   // contact, 225° .. 270°

Transfinite Curve{1, 5} = 2 * n + 1;
Transfinite Curve{3} = 2 * n + 1;
Transfinite Curve{2, 4} = 5 * n + 1;

Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};
Point{1} In Surface{1};

Field[1] = MathEval;
Field[1].F = Sprintf("%.17g + %.17g * (1 - Sqrt(x*x + y*y))", hb, G);
Background Field = 1;
Mesh.MeshSizeMax = H;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;

Physical Curve("contact") = {5, 1};
Physical Curve("load") = {3};
Physical Curve("free") = {2, 4};
Physical Surface("body") = {1};
