// A half cylinder (the lower half of a disk of radius R) pressed onto a rigid flat:
// Hertz's line contact, in plane strain. The flat top is held; the flat below moves up.
R = 1.0;      // radius
h0 = 0.002;   // element size at the lowest point (0, -R), where contact starts
g = 0.1;      // growth of the element size with the distance from that point

Point(1) = {0, 0, 0};                    // centre of the arc
Point(2) = {-R, 0, 0};
Point(3) = {-R*Sin(Pi/6), -R*Cos(Pi/6), 0};
Point(4) = {0, -R, 0};                   // the lowest point
Point(5) = {R*Sin(Pi/6), -R*Cos(Pi/6), 0};
Point(6) = {R, 0, 0};

Circle(1) = {2, 1, 3};                   // free
Circle(2) = {3, 1, 4};                   // contact: the lowest 60° of the arc
Circle(3) = {4, 1, 5};                   // contact
Circle(4) = {5, 1, 6};                   // free
Line(5) = {6, 2};                        // the held top
Curve Loop(1) = {1, 2, 3, 4, 5};
Plane Surface(1) = {1};

Field[1] = MathEval;
Field[1].F = Sprintf("%g + %g * Sqrt(x*x + (y + %g)^2)", h0, g, R);
Background Field = 1;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 0;

Physical Curve("contact") = {2, 3};
Physical Curve("free") = {1, 4};
Physical Curve("top") = {5};
Physical Surface("body") = {1};
