// A 0.1 × 0.05 m plate meshed with quadrilaterals (recombined triangles): a mesh body whose
// elements the FE reference on mesh bodies does not take (it takes triangles and tetrahedra).
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 0.1, 0.05};
Mesh.RecombineAll = 1;
e = 1e-6;
Physical Curve("left") = Curve In BoundingBox{-e, -e, -e, e, 0.05 + e, e};
