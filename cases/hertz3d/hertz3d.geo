// Quarter of the lower half of the unit ball (x >= 0, y >= 0, z <= 0), for the 3D Hertz case
// (hertz3d.toml): pressed by a pressure on its flat top (z = 0) onto the rigid plane z = -1.
// Symmetry planes x = 0 and y = 0 carry u_x = 0 / u_y = 0.
// Mesh size h near the pole (0, 0, -1) up to the distance 2*r, growing linearly to hmax at
// the distance dmax:  gmsh -3 hertz3d.geo -setnumber h 0.004 -o hertz3d.msh
SetFactory("OpenCASCADE");
DefineConstant[ h = 0.01, r = 0.1, hmax = 0.12, dmax = 0.7 ];
Sphere(1) = {0, 0, 0, 1};
Box(2) = {0, 0, -1, 1, 1, 1};
BooleanIntersection(3) = { Volume{1}; Delete; }{ Volume{2}; Delete; };
eps = 1e-6;
top() = Surface In BoundingBox{-eps, -eps, -eps, 1 + eps, 1 + eps, eps};
symx() = Surface In BoundingBox{-eps, -eps, -1 - eps, eps, 1 + eps, eps};
symy() = Surface In BoundingBox{-eps, -eps, -1 - eps, 1 + eps, eps, eps};
all() = Surface{:};
curved() = all();
curved() -= top();
curved() -= symx();
curved() -= symy();
Physical Volume("body") = {3};
Physical Surface("load") = {top()};
Physical Surface("sym_x") = {symx()};
Physical Surface("sym_y") = {symy()};
Physical Surface("contact") = {curved()};
Field[1] = MathEval;
Field[1].F = Sprintf("%g + (%g - %g) * Max(0, Min(1, (Sqrt(x*x + y*y + (z+1)*(z+1)) - 2*%g) / (%g - 2*%g)))", h, hmax, h, r, dmax, r);
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm3D = 10;
