// A rigid ellipsoidal indenter for examples/indent_stl.toml: semi-axes 0.4 (x), 0.25 (y),
// 0.3 (z), its lowest point 0.05 below the top face (z = 0.5) of cases/blocks/block3d.msh.
// gmsh -2 indenter_ellipsoid.geo -format stl -bin -o indenter_ellipsoid.stl
SetFactory("OpenCASCADE");
Sphere(1) = {0, 0, 0, 1};
Dilate {{0, 0, 0}, {0.4, 0.25, 0.3}} { Volume{1}; }
Translate {0, 0, 0.75} { Volume{1}; }
Mesh.MeshSizeMin = 0.01;
Mesh.MeshSizeMax = 0.05;
// Finer near the bottom, where the block is touched.
Point(100) = {0, 0, 0.45};
Field[1] = Distance;
Field[1].PointsList = {100};
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = 0.012;
Field[2].SizeMax = 0.05;
Field[2].DistMin = 0.1;
Field[2].DistMax = 0.3;
Background Field = 2;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
