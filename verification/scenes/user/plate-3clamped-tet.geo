// The plate of verification/cases/plate-3clamped, 4 × 3 × 0.25 m (x × y × z), drawn with
// OpenCASCADE; Gmsh meshes it with unstructured tetrahedra. The top face z = 0.25 is the
// physical group "top".
SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 4, 3, 0.25};
e = 1e-6;
Physical Surface("top") = Surface In BoundingBox{-e, -e, 0.25 - e, 4 + e, 3 + e, 0.25 + e};
Physical Volume("plate") = {1};
