// The cantilever of verification/cases/cantilever, 3.5 × 0.3 × 0.4 m (x × y × z), drawn with
// OpenCASCADE; Gmsh meshes it with unstructured tetrahedra. Physical groups: the face x = 0
// ("root") and the top face z = 0.4 ("top").
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 3.5, 0.3, 0.4};
e = 1e-6;
Physical Surface("root") = Surface In BoundingBox{-e, -e, -e, e, 0.3 + e, 0.4 + e};
Physical Surface("top") = Surface In BoundingBox{-e, -e, 0.4 - e, 3.5 + e, 0.3 + e, 0.4 + e};
Physical Volume("beam") = {1};
