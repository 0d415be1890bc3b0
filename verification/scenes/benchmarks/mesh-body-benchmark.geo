// The part of mesh-body-benchmark.yaml: a 0.2 × 0.1 × 0.1 m block with a bore of radius 25 mm
// through it along z, drawn with OpenCASCADE; Gmsh meshes it with unstructured tetrahedra at the
// scene's lattice.spacing. Physical groups: the face x = 0 ("root").
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 0.2, 0.1, 0.1};
Cylinder(2) = {0.1, 0.05, 0, 0, 0, 0.1, 0.025};
BooleanDifference(3) = {Volume{1}; Delete;}{Volume{2}; Delete;};
e = 1e-6;
Physical Surface("root") = Surface In BoundingBox{-e, -e, -e, e, 0.1 + e, 0.1 + e};
Physical Volume("part") = {3};
