// A thin strip, 2 m × 0.1 m (x × y), drawn with OpenCASCADE; Gmsh meshes it with unstructured
// triangles at the scene's lattice.spacing, two elements through its depth.
SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 2, 0.1};
Physical Surface("strip") = {1};
