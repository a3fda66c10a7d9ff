// A half annulus (inner radius 0.6, outer 1), its outer arc the contact boundary, pressed onto
// a rigid plane through its two flat ends ("ends"); graded: h at the bottom, 8h at the ends.
// Meshed by scripts/bench-shapes: gmsh -2 arch.geo -setnumber h 0.006 -format msh41 -o ../meshes/arch_h0.006.msh
If (!Exists(h)) h = 0.01; EndIf
Ri = 0.6; Ro = 1.0;
Point(1) = {0,0,0,h};
Point(2) = {-Ro,0,0,8*h}; Point(3) = {0,-Ro,0,h}; Point(4) = {Ro,0,0,8*h};
Point(5) = {Ri,0,0,8*h}; Point(6) = {0,-Ri,0,3*h}; Point(7) = {-Ri,0,0,8*h};
Circle(1) = {2,1,3}; Circle(2) = {3,1,4};
Line(3) = {4,5};
Circle(4) = {5,1,6}; Circle(5) = {6,1,7};
Line(6) = {7,2};
Curve Loop(1) = {1,2,3,4,5,6};
Plane Surface(1) = {1};
Physical Curve("contact") = {1,2};
Physical Curve("ends") = {3,6};
Physical Curve("inner") = {4,5};
Physical Surface("body") = {1};
