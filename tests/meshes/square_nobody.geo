// Unit square with physical boundary lines but NO physical surface: meshed with
// -save_all, gmsh writes the triangles without any physical group (a test of the reader's
// refusal). gmsh -2 square_nobody.geo -save_all -format msh41 -o square_nobody_saveall.msh
Include "square.geo";
Delete Physicals;
Physical Curve("bottom") = {1};
Physical Curve("left") = {4};
